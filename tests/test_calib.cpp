// Calibration readers and the Basalt writer on synthetic files: known answers, round trips, and
// errors that name the file and the field.

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "formats/calib/calibration_io.h"
#include "formats/image/png_io.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using voca::SE3d;

using voca::test::expectError;
using voca::test::writeText;

std::string errorOf(const fs::path& path) {
  return voca::test::inputErrorOf([&] { voca::loadCalibration(path); });
}

// The camera poses used below: cam1 11 cm to the right of cam0 and slightly rotated, both
// rotated relative to the IMU as in EuRoC (camera x = -IMU y).
SE3d imuFromCam0() {
  return SE3d(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ())),
              Eigen::Vector3d(-0.02, -0.06, 0.01));
}
SE3d cam0FromCam1() {
  return SE3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.01, Eigen::Vector3d(0.3, 1.0, 0.2).normalized())),
              Eigen::Vector3d(0.11, 0.001, -0.002));
}

voca::StereoRig makeRig(std::string_view model0, std::vector<double> params0, std::string_view model1,
                        std::vector<double> params1) {
  voca::StereoRig rig;
  rig.cameras.push_back({voca::GenericCamera<double>::fromParams(model0, params0), 752, 480, imuFromCam0()});
  rig.cameras.push_back(
      {voca::GenericCamera<double>::fromParams(model1, params1), 640, 512, imuFromCam0() * cam0FromCam1()});
  return rig;
}

void checkPoseNear(const SE3d& a, const SE3d& b, double tolerance) {
  CHECK((a.translation() - b.translation()).norm() < tolerance);
  CHECK((a.inverse() * b).so3().log().norm() < tolerance);
}

// A Basalt JSON text of a two-camera ds rig, for editing into malformed variants.
json basaltJson() {
  json pose = {{"px", 0.1}, {"py", 0.0}, {"pz", 0.0}, {"qx", 0.0}, {"qy", 0.0}, {"qz", 0.0}, {"qw", 1.0}};
  json ds = {
      {"camera_type", "ds"},
      {"intrinsics", {{"fx", 350.0}, {"fy", 349.0}, {"cx", 366.0}, {"cy", 249.0}, {"xi", -0.24}, {"alpha", 0.57}}}};
  json value0 = {{"T_imu_cam", {pose, pose}}, {"intrinsics", {ds, ds}}, {"resolution", {{752, 480}, {752, 480}}}};
  value0["T_imu_cam"][0]["px"] = 0.0;
  return {{"value0", value0}};
}

}  // namespace

TEST_CASE("Basalt JSON save/load round trip for every camera model") {
  voca::test::ScratchDir dir("calib-roundtrip");
  const std::vector<voca::StereoRig> rigs = {
      makeRig("ds", {349.7, 348.7, 365.9, 249.3, -0.2409573942178872, 0.566996899163044}, "kb4",
              {190.97, 190.96, 254.93, 256.89, 0.0034823894022493434, 0.0007150348452162257, -0.0020532361418706202,
               0.00020293673591811182}),
      makeRig("pinhole-radtan8",
              {458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0.01, 0.002,
               -0.0003, 0.00004},
              "eucm", {460.76, 459.37, 365.82, 249.35, 0.5903, 1.1285}),
      makeRig("pinhole", {707.0912, 707.0912, 601.8873, 183.1104}, "pinhole", {707.0, 708.0, 600.0, 180.0}),
  };
  for (const voca::StereoRig& rig : rigs) {
    CAPTURE(rig.cameras[0].camera.modelName());
    const fs::path file = dir / "rig_calib.json";
    voca::saveBasaltCalibration(rig, file);
    const voca::StereoRig back = voca::loadCalibration(file);
    CHECK(back.body_frame == "imu");
    CHECK(back.source == file.string());
    REQUIRE(back.cameras.size() == 2);
    for (size_t i = 0; i < 2; ++i) {
      CHECK(back.cameras[i].camera.modelName() == rig.cameras[i].camera.modelName());
      // JSON stores doubles with 17 significant digits: parameters come back bit-exact.
      CHECK(back.cameras[i].camera.params() == rig.cameras[i].camera.params());
      CHECK(back.cameras[i].width == rig.cameras[i].width);
      CHECK(back.cameras[i].height == rig.cameras[i].height);
      // Poses pass through a re-normalised quaternion: equal to rounding (1e-12 m / rad).
      checkPoseNear(back.cameras[i].T_body_cam, rig.cameras[i].T_body_cam, 1e-12);
    }
    checkPoseNear(back.T_cam0_cam1(), cam0FromCam1(), 1e-12);
    CHECK(back.baselineM() == doctest::Approx(cam0FromCam1().translation().norm()).epsilon(1e-12));
  }
}

TEST_CASE("malformed Basalt JSON names the file and the field") {
  voca::test::ScratchDir dir("calib-json-bad");
  const fs::path file = dir / "euroc.json";
  const auto errorFor = [&](const json& j) {
    writeText(file, j.dump(2));
    return errorOf(file);
  };
  expectError(errorFor(basaltJson()), "(no error)");

  json j = basaltJson();
  j["value0"]["intrinsics"][1]["intrinsics"].erase("fx");
  expectError(errorFor(j), "euroc.json: value0.intrinsics[1].intrinsics.fx: missing");

  j = basaltJson();
  j["value0"]["intrinsics"][0]["intrinsics"]["fy"] = "349";
  expectError(errorFor(j), "euroc.json: value0.intrinsics[0].intrinsics.fy: expected a number, got a string");

  j = basaltJson();
  j["value0"]["intrinsics"][1]["camera_type"] = "fisheye";
  const std::string unknown = errorFor(j);
  expectError(unknown, "euroc.json: value0.intrinsics[1].camera_type: unknown camera type 'fisheye'");
  expectError(unknown, "ds");

  j = basaltJson();
  j["value0"]["intrinsics"][0]["intrinsics"]["k5"] = 0.1;
  expectError(errorFor(j), "value0.intrinsics[0].intrinsics.k5: unknown parameter for camera type ds");

  j = basaltJson();
  j["value0"]["intrinsics"][0]["intrinsics"]["alpha"] = 1.5;
  expectError(errorFor(j), "value0.intrinsics[0].intrinsics: camera model 'ds': alpha");

  j = basaltJson();
  j["value0"]["resolution"][1] = json::array({752});
  expectError(errorFor(j), "value0.resolution[1]: expected [width, height]");

  j = basaltJson();
  j["value0"]["resolution"][0][0] = 752.5;
  expectError(errorFor(j), "value0.resolution[0][0]: expected an image size in pixels, 1 to 16384, got 752.5");

  // Larger than any camera: refused here rather than failing to allocate the pipeline's buffers.
  j = basaltJson();
  j["value0"]["resolution"][1][1] = 100000;
  expectError(errorFor(j), "value0.resolution[1][1]: expected an image size in pixels, 1 to 16384, got 100000");

  j = basaltJson();
  j["value0"]["T_imu_cam"].erase(1);
  expectError(errorFor(j), "value0.T_imu_cam: has 1 entries but value0.intrinsics has 2");

  j = basaltJson();
  j["value0"]["T_imu_cam"][1]["qw"] = 0.0;
  expectError(errorFor(j), "value0.T_imu_cam[1]: quaternion (qx qy qz qw) has norm 0, expected 1");

  j = basaltJson();
  j["value0"]["T_imu_cam"][0].erase("pz");
  expectError(errorFor(j), "value0.T_imu_cam[0].pz: missing");

  j = basaltJson();
  j["value0"]["intrinsics"] = json::object();
  expectError(errorFor(j), "value0.intrinsics: expected an array, got an object");

  j = basaltJson();
  j["value0"]["intrinsics"].erase(1);
  expectError(errorFor(j), "value0.intrinsics: a stereo rig needs at least 2 cameras, got 1");

  expectError(errorFor(json{{"config.x", 1}}), "euroc.json: value0: missing");
  expectError(errorFor(json::array({1, 2})), "euroc.json: expected an object, got an array");

  writeText(file, "{\"value0\": {\"T_imu_cam\": [");
  expectError(errorOf(file), "euroc.json: malformed JSON");
  writeText(file, "");
  expectError(errorOf(file), "euroc.json: malformed JSON");
}

namespace {

// A Kalibr camchain in the EuRoC style; `cam1_extrinsics` replaces cam1's extrinsics lines.
std::string camchain(const std::string& cam0_extra, const std::string& cam1_extrinsics,
                     const std::string& cam1_intrinsics = "[457.587, 456.134, 379.999, 255.238]") {
  return "%YAML:1.0\ncam0:\n" + cam0_extra +
         "  camera_model: pinhole\n"
         "  distortion_coeffs: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]\n"
         "  distortion_model: radtan\n"
         "  intrinsics: [458.654, 457.296, 367.215, 248.375]\n"
         "  resolution: [752, 480]\n"
         "cam1:\n" +
         cam1_extrinsics +
         "  camera_model: pinhole\n"
         "  distortion_coeffs: [0.0034, 0.0017, -0.0026, 0.00033]\n"
         "  distortion_model: equidistant\n"
         "  intrinsics: " +
         cam1_intrinsics +
         "\n"
         "  resolution: [512, 512]\n";
}

std::string matrixYaml(const std::string& key, const SE3d& T) {
  std::ostringstream out;
  out.precision(17);
  out << "  " << key << ":\n";
  const Eigen::Matrix4d m = T.matrix();
  for (int r = 0; r < 4; ++r)
    out << "    - [" << m(r, 0) << ", " << m(r, 1) << ", " << m(r, 2) << ", " << m(r, 3) << "]\n";
  return out.str();
}

}  // namespace

TEST_CASE("Kalibr camchain: IMU extrinsics, camera-only chains and models") {
  voca::test::ScratchDir dir("calib-kalibr");
  const fs::path file = dir / "camchain.yaml";
  const SE3d T_imu_cam1 = imuFromCam0() * cam0FromCam1();

  SUBCASE("T_cam_imu for both cameras: body = IMU") {
    writeText(file, camchain(matrixYaml("T_cam_imu", imuFromCam0().inverse()),
                             matrixYaml("T_cam_imu", T_imu_cam1.inverse())));
    const voca::StereoRig rig = voca::loadCalibration(file);
    CHECK(rig.body_frame == "imu");
    CHECK(rig.cameras[0].camera.modelName() == "pinhole-radtan8");
    CHECK(rig.cameras[1].camera.modelName() == "kb4");
    // radtan k1 k2 p1 p2 land in Basalt's order with k3..k6 = 0.
    const std::vector<double> p0 = rig.cameras[0].camera.params();
    CHECK(p0[4] == -0.28340811);
    CHECK(p0[7] == 1.76187114e-05);
    CHECK(p0[8] == 0.0);
    CHECK(rig.cameras[1].width == 512);
    // The files print 17 digits; the rotation is re-orthonormalised: 1e-12.
    checkPoseNear(rig.cameras[0].T_body_cam, imuFromCam0(), 1e-12);
    checkPoseNear(rig.T_cam0_cam1(), cam0FromCam1(), 1e-12);
  }
  SUBCASE("T_imu_cam (OpenVINS style) also means body = IMU") {
    writeText(file, camchain(matrixYaml("T_imu_cam", imuFromCam0()), matrixYaml("T_imu_cam", T_imu_cam1)));
    const voca::StereoRig rig = voca::loadCalibration(file);
    CHECK(rig.body_frame == "imu");
    checkPoseNear(rig.cameras[1].T_body_cam, T_imu_cam1, 1e-12);
  }
  SUBCASE("camera-only chain: body = cam0, cam1 from T_cn_cnm1") {
    writeText(file, camchain("", matrixYaml("T_cn_cnm1", cam0FromCam1().inverse())));
    const voca::StereoRig rig = voca::loadCalibration(file);
    CHECK(rig.body_frame == "cam0");
    checkPoseNear(rig.cameras[0].T_body_cam, SE3d(), 1e-15);
    checkPoseNear(rig.cameras[1].T_body_cam, cam0FromCam1(), 1e-12);
    // cam1 is to the right of cam0 (+x), as in every dataset here.
    CHECK(rig.T_cam0_cam1().translation().x() > 0.1);
  }
  SUBCASE("IMU chain where cam1 has only T_cn_cnm1") {
    writeText(file, camchain(matrixYaml("T_cam_imu", imuFromCam0().inverse()),
                             matrixYaml("T_cn_cnm1", cam0FromCam1().inverse())));
    const voca::StereoRig rig = voca::loadCalibration(file);
    CHECK(rig.body_frame == "imu");
    checkPoseNear(rig.cameras[1].T_body_cam, T_imu_cam1, 1e-12);
  }
  SUBCASE("Kalibr ds and eucm models put their shape parameters first") {
    writeText(file,
              "cam0:\n  camera_model: ds\n  distortion_model: none\n  distortion_coeffs: []\n"
              "  intrinsics: [-0.24, 0.57, 350.0, 349.0, 366.0, 249.0]\n  resolution: [752, 480]\n"
              "cam1:\n  camera_model: eucm\n  distortion_model: none\n"
              "  intrinsics: [0.59, 1.13, 460.0, 459.0, 365.0, 249.0]\n  resolution: [752, 480]\n" +
                  matrixYaml("T_cn_cnm1", cam0FromCam1().inverse()));
    const voca::StereoRig rig = voca::loadCalibration(file);
    CHECK(rig.cameras[0].camera.params() == std::vector<double>{350.0, 349.0, 366.0, 249.0, -0.24, 0.57});
    CHECK(rig.cameras[1].camera.modelName() == "eucm");
    CHECK(rig.cameras[1].camera.params() == std::vector<double>{460.0, 459.0, 365.0, 249.0, 0.59, 1.13});
  }
}

TEST_CASE("malformed Kalibr camchains name the file and the field") {
  voca::test::ScratchDir dir("calib-kalibr-bad");
  const fs::path file = dir / "chain.yaml";
  const std::string good1 = matrixYaml("T_cn_cnm1", cam0FromCam1().inverse());
  const auto errorFor = [&](const std::string& text) {
    writeText(file, text);
    return errorOf(file);
  };
  CHECK(errorFor(camchain("", good1)) == "(no error)");
  expectError(errorFor(camchain("", good1, "[457.5, 456.1, 380.0]")),
              "chain.yaml: cam1 (line 9): Kalibr camera_model 'pinhole' with distortion_model 'equidistant': "
              "intrinsics must have 4 values");
  expectError(errorFor(camchain("", good1, "[457.5, fast, 380.0, 255.0]")),
              "chain.yaml: cam1.intrinsics[1] (line 17): expected a number, got 'fast'");
  expectError(errorFor(camchain("", good1, "abc")), "cam1.intrinsics (line 17): expected a list of numbers, got 'abc'");
  // Non-finite values and decimal commas are not numbers; a leading '+' is (YAML allows it).
  expectError(errorFor(camchain("", good1, "[457.5, .nan, 380.0, 255.0]")),
              "chain.yaml: cam1.intrinsics[1] (line 17): expected a number, got '.nan'");
  expectError(errorFor(camchain("", good1, "[457.5, .inf, 380.0, 255.0]")),
              "chain.yaml: cam1.intrinsics[1] (line 17): expected a number, got '.inf'");
  expectError(errorFor(camchain("", good1, "[457.5, \"456,1\", 380.0, 255.0]")),
              "chain.yaml: cam1.intrinsics[1] (line 17): expected a number, got '456,1'");
  CHECK(errorFor(camchain("", good1, "[457.5, +456.1, 380.0, 255.0]")) == "(no error)");
  expectError(errorFor(camchain("", "")), "chain.yaml: cam1.T_cn_cnm1: missing");
  SE3d scaled;
  std::string bad = matrixYaml("T_cn_cnm1", scaled);
  bad.replace(bad.find("[1, 0, 0, 0]"), 12, "[2, 0, 0, 0]");
  expectError(errorFor(camchain("", bad)), "cam1.T_cn_cnm1 (line 10): rotation block is not a rotation");
  std::string short_row = good1;
  short_row.erase(short_row.rfind(", 1]"), 3);
  expectError(errorFor(camchain("", short_row)),
              "cam1.T_cn_cnm1[3] (line 13): expected a list of 4 numbers, got a list of 3");

  std::string no_model = camchain("", good1);
  no_model.erase(no_model.find("  camera_model: pinhole\n"), 24);
  expectError(errorFor(no_model), "chain.yaml: cam0.camera_model: missing (in the map starting at line 3)");
  std::string fov = camchain("", good1);
  fov.replace(fov.find("radtan"), 6, "fov");
  expectError(errorFor(fov), "cam0 (line 3): Kalibr camera_model 'pinhole' with distortion_model 'fov': unsupported");

  expectError(errorFor("cam0: [unclosed\n"), "chain.yaml:2: malformed YAML");
  expectError(errorFor("just a string\n"), "chain.yaml (line 1): expected a map of fields, got 'just a string'");
  std::string mono = camchain("", good1);
  mono.resize(mono.find("cam1:"));
  expectError(errorFor(mono), "chain.yaml: cam1: missing");
}

namespace {

std::string sensorYaml(const SE3d& T_BS, const std::string& intrinsics = "[458.654, 457.296, 367.215, 248.375]") {
  std::ostringstream out;
  out.precision(17);
  out << "%YAML:1.0\nsensor_type: camera\nT_BS:\n  cols: 4\n  rows: 4\n  data: [";
  const Eigen::Matrix4d m = T_BS.matrix();
  for (int i = 0; i < 16; ++i) out << (i ? ", " : "") << m(i / 4, i % 4);
  out << "]\nrate_hz: 20\nresolution: [752, 480]\ncamera_model: pinhole\nintrinsics: " << intrinsics
      << "\ndistortion_model: radial-tangential\ndistortion_coefficients: [-0.28, 0.07, 0.0002, 1.8e-05]\n";
  return out.str();
}

}  // namespace

TEST_CASE("EuRoC sensor.yaml folders") {
  voca::test::ScratchDir dir("calib-euroc");
  const fs::path mav0 = dir / "mav0";
  writeText(mav0 / "cam0/sensor.yaml", sensorYaml(imuFromCam0()));
  writeText(mav0 / "cam1/sensor.yaml", sensorYaml(imuFromCam0() * cam0FromCam1()));
  for (const fs::path& path : {dir.path(), mav0, mav0 / "cam1" / "sensor.yaml"}) {
    const voca::StereoRig rig = voca::loadCalibration(path);
    CHECK(rig.body_frame == "euroc-body");
    REQUIRE(rig.cameras.size() == 2);
    CHECK(rig.cameras[1].camera.modelName() == "pinhole-radtan8");
    CHECK(rig.cameras[1].width == 752);
    checkPoseNear(rig.T_cam0_cam1(), cam0FromCam1(), 1e-12);
  }
  writeText(mav0 / "cam1/sensor.yaml", sensorYaml(SE3d(), "[458.654, 457.296]"));
  expectError(errorOf(mav0),
              "cam1/sensor.yaml: Kalibr camera_model 'pinhole' with distortion_model 'radtan': "
              "intrinsics must have 4 values");
  std::string text = sensorYaml(SE3d());
  text.erase(text.find("T_BS:"), text.find("rate_hz") - text.find("T_BS:"));
  writeText(mav0 / "cam1/sensor.yaml", text);
  expectError(errorOf(mav0), "cam1/sensor.yaml: T_BS: missing");
  text = sensorYaml(SE3d());
  text.replace(text.find("[1, 0, 0, 0,"), 12, "[1, 0, 0,");
  writeText(mav0 / "cam1/sensor.yaml", text);
  expectError(errorOf(mav0), "cam1/sensor.yaml: T_BS.data (line 6): expected a list of 16 numbers, got a list of 15");
  fs::remove(mav0 / "cam1/sensor.yaml");
  expectError(errorOf(mav0), "cam1/sensor.yaml: missing");
}

TEST_CASE("KITTI calib.txt: pinhole cameras, cam1 to the right by -P1[0,3]/fx") {
  voca::test::ScratchDir dir("calib-kitti");
  const fs::path seq = dir / "06";
  fs::create_directories(seq / "image_0");
  voca::writePngGray(seq / "image_0" / "000000.png", voca::GrayImage(124, 37, 0).view());
  const std::string p0 = "P0: 7.07e+02 0 6.01e+02 0 0 7.07e+02 1.83e+02 0 0 0 1 0\n";
  writeText(seq / "calib.txt", p0 + "P1: 7.07e+02 0 6.01e+02 -3.535e+02 0 7.07e+02 1.83e+02 0 0 0 1 0\nTr: 1 2 3\n");
  for (const fs::path& path : {seq, seq / "calib.txt"}) {
    const voca::StereoRig rig = voca::loadCalibration(path);
    CHECK(rig.body_frame == "cam0");
    CHECK(rig.cameras[0].camera.modelName() == "pinhole");
    CHECK(rig.cameras[1].camera.params() == std::vector<double>{707.0, 707.0, 601.0, 183.0});
    CHECK(rig.cameras[0].width == 124);
    CHECK(rig.cameras[1].height == 37);
    // 353.5 / 707 = 0.5 m exactly; rectified: no rotation.
    CHECK(rig.T_cam0_cam1().translation().isApprox(Eigen::Vector3d(0.5, 0, 0), 1e-15));
    CHECK(rig.T_cam0_cam1().so3().log().norm() == 0.0);
  }
  writeText(seq / "calib.txt", p0);
  expectError(errorOf(seq / "calib.txt"), "calib.txt: P1: missing");
  writeText(seq / "calib.txt", p0 + "P1: 7.07e+02 0 6.01e+02 -3.5e+02 0 7.07e+02 1.83e+02 0 0 0 1\n");
  expectError(errorOf(seq / "calib.txt"), "calib.txt:2: P1: expected 12 numbers (3x4 row-major), got 11");
  writeText(seq / "calib.txt", p0 + "P1: 7.07e+02 0 6.01e+02 -3.5e+02 0 7.07e+02 1.83e+02 0 0 0 one 0\n");
  expectError(errorOf(seq / "calib.txt"), "calib.txt:2: P1: 'one' is not a number");
  writeText(seq / "calib.txt", p0 + "P1 7.07e+02\n");
  expectError(errorOf(seq / "calib.txt"), "calib.txt:2: expected '<name>: <numbers>'");
  writeText(seq / "calib.txt", p0 + "P1: -7.07e+02 0 6.01e+02 -3.5e+02 0 7.07e+02 1.83e+02 0 0 0 1 0\n");
  expectError(errorOf(seq / "calib.txt"), "calib.txt:2: P1: camera model 'pinhole': focal length fx");
  writeText(seq / "calib.txt", p0 + "P1: 7.07e+02 3 6.01e+02 -3.5e+02 0 7.07e+02 1.83e+02 0 0 0 1 0\n");
  expectError(errorOf(seq / "calib.txt"), "calib.txt:2: P1: expected a rectified projection");
  fs::remove_all(seq / "image_0");
  expectError(errorOf(seq / "calib.txt"), "calib.txt: image size unknown");
}

TEST_CASE("loadCalibration explains what it cannot read") {
  voca::test::ScratchDir dir("calib-dispatch");
  expectError(errorOf(dir / "nothing.json"), "nothing.json: calibration not found");
  writeText(dir / "calib.xml", "<xml/>");
  expectError(errorOf(dir / "calib.xml"), "calib.xml: unknown calibration format");
  fs::create_directories(dir / "empty");
  const std::string error = errorOf(dir / "empty");
  expectError(error, "no calibration found in this folder");
  expectError(error, "sensor.yaml");
  expectError(error, "calib.txt");
  // A folder holding a Basalt calibration next to a dataset.
  voca::saveBasaltCalibration(makeRig("pinhole", {500, 500, 320, 240}, "pinhole", {500, 500, 320, 240}),
                              dir / "empty" / "rig_calib.json");
  CHECK(voca::loadCalibration(dir / "empty").cameras.size() == 2);
  // One camera is not a stereo rig.
  voca::StereoRig mono;
  mono.source = "mono";
  mono.cameras.resize(1);
  CHECK_THROWS_AS(mono.T_cam0_cam1(), voca::InputError);
}

TEST_CASE("loadCalibration refuses a rig whose right camera sits on the left one") {
  voca::test::ScratchDir dir("calib-baseline");
  const fs::path file = dir / "rig_calib.json";
  json j = basaltJson();
  // Both poses the same: no baseline to triangulate with.
  j["value0"]["T_imu_cam"][1]["px"] = 0.0;
  writeText(file, j.dump(2));
  const std::string error = errorOf(file);
  expectError(error, "rig_calib.json: cam1 is 0 mm from cam0: a stereo rig needs a baseline of at least 1 mm");
  // A baseline in the wrong unit (0.11 mm instead of 0.11 m), through a folder as well.
  j["value0"]["T_imu_cam"][1]["px"] = 0.00011;
  writeText(file, j.dump(2));
  expectError(errorOf(dir.path()), "cam1 is 0.11 mm from cam0");
  // Two millimetres is a (small) rig.
  j["value0"]["T_imu_cam"][1]["px"] = 0.002;
  writeText(file, j.dump(2));
  CHECK(voca::loadCalibration(file).baselineM() == doctest::Approx(0.002));
}
