#include "voca/synth/rigs.h"

#include <array>

namespace voca::synth {

namespace {

SE3d fromRows(const std::array<double, 12>& m) {
  Eigen::Matrix<double, 3, 4> rows;
  rows << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8], m[9], m[10], m[11];
  return SE3d(rows);
}

CameraCalibration makeCamera(std::string_view model, std::initializer_list<double> params, int width, int height,
                             const SE3d& T_body_cam) {
  const std::vector<double> values(params);
  return {GenericCamera<double>::fromParams(model, values), width, height, T_body_cam};
}

}  // namespace

StereoRig eurocRig() {
  StereoRig rig;
  rig.source = "built-in EuRoC (Kalibr camchain of the EuRoC MAV dataset)";
  rig.body_frame = "imu";
  // Kalibr radtan (k1 k2 p1 p2) maps to pinhole-radtan8 with k3..k6 = 0.
  rig.cameras.push_back(makeCamera(
      "pinhole-radtan8",
      {458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0.0, 0.0, 0.0, 0.0},
      752, 480,
      fromRows({0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975, 0.999557249008, 0.0149672133247,
                0.025715529948, -0.064676986768, -0.0257744366974, 0.00375618835797, 0.999660727178,
                0.00981073058949})));
  rig.cameras.push_back(makeCamera(
      "pinhole-radtan8",
      {457.587, 456.134, 379.999, 255.238, -0.28368365, 0.07451284, -0.00010473, -3.55590700e-05, 0.0, 0.0, 0.0, 0.0},
      752, 480,
      fromRows({0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556, 0.999598781151, 0.0130119051815,
                0.0251588363115, 0.0453689425024, -0.0253898008918, 0.0179005838253, 0.999517347078,
                0.00786212447038})));
  return rig;
}

StereoRig tumviRig() {
  StereoRig rig;
  rig.source = "built-in TUM-VI 512 (Kalibr camchain of the TUM-VI dataset)";
  rig.body_frame = "imu";
  // The camchain gives T_cam_imu; the rig stores T_imu_cam.
  rig.cameras.push_back(
      makeCamera("kb4",
                 {190.97847715128717, 190.9733070521226, 254.93170605935475, 256.8974428996504, 0.0034823894022493434,
                  0.0007150348452162257, -0.0020532361418706202, 0.00020293673591811182},
                 512, 512,
                 fromRows({-0.9995250378696743, 0.029615343885863205, -0.008522328211654736, 0.04727988224914392,
                           0.0075019185074052044, -0.03439736061393144, -0.9993800792498829, -0.047443232143367084,
                           -0.02989013031643309, -0.998969345370175, 0.03415885127385616, -0.0681999605066297})
                     .inverse()));
  rig.cameras.push_back(
      makeCamera("kb4",
                 {190.44236969414825, 190.4344384721956, 252.59949716835982, 254.91723064636983, 0.0034003170790442797,
                  0.001766278153469831, -0.00266312569781606, 0.0003299517423931039},
                 512, 512,
                 fromRows({-0.9995110484978581, 0.030299116376600627, -0.0077218830287333565, -0.053697434688869734,
                           0.008104079263822521, 0.012511643720192351, -0.9998888851620987, -0.046131737923635924,
                           -0.030199136245891378, -0.9994625667418545, -0.012751072573940885, -0.07149261284195751})
                     .inverse()));
  return rig;
}

std::optional<StereoRig> builtinRig(std::string_view name) {
  if (name == "euroc") return eurocRig();
  if (name == "tumvi") return tumviRig();
  return std::nullopt;
}

RayTable makeRayTable(const CameraCalibration& camera) {
  return RayTable(camera.width, camera.height, [&camera](const Eigen::Vector2d& uv, Eigen::Vector3d& bearing) {
    return camera.camera.unproject(uv, bearing);
  });
}

}  // namespace voca::synth
