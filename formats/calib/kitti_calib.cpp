// KITTI odometry calib.txt: rectified 3x4 projection matrices "P0: ..." and "P1: ...".

#include <charconv>
#include <fstream>
#include <map>
#include <sstream>

#include "formats/calib/calibration_io.h"
#include "formats/image/png_io.h"
#include "voca/core/error.h"

namespace voca {
namespace fs = std::filesystem;

namespace {

using Mat34 = Eigen::Matrix<double, 3, 4>;

struct Projection {
  Mat34 matrix;
  int line = 0;
};

std::map<std::string, Projection> readProjections(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open calibration");
  std::map<std::string, Projection> projections;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    const size_t colon = text.find(':');
    if (colon == std::string::npos) {
      if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
      throw InputError(path.string() + ":" + std::to_string(line) + ": expected '<name>: <numbers>', got '" + text +
                       "'");
    }
    const std::string key = text.substr(0, colon);
    // Only the P rows matter here; KITTI files also carry Tr (velodyne) and others we do not use.
    if (key.empty() || key[0] != 'P') continue;
    std::istringstream values(text.substr(colon + 1));
    std::vector<double> numbers;
    std::string token;
    while (values >> token) {
      double v = 0.0;
      const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
      if (ec != std::errc() || end != token.data() + token.size() || !std::isfinite(v)) {
        throw InputError(path.string() + ":" + std::to_string(line) + ": " + key + ": '" + token + "' is not a number");
      }
      numbers.push_back(v);
    }
    if (numbers.size() != 12) {
      throw InputError(path.string() + ":" + std::to_string(line) + ": " + key +
                       ": expected 12 numbers (3x4 row-major), got " + std::to_string(numbers.size()));
    }
    Projection projection;
    projection.line = line;
    projection.matrix = Eigen::Map<const Eigen::Matrix<double, 3, 4, Eigen::RowMajor>>(numbers.data());
    projections[key] = projection;
  }
  return projections;
}

// calib.txt has no image size; take it from the first left image of the sequence.
std::pair<int, int> imageSize(const fs::path& calib_txt) {
  const fs::path folder = calib_txt.parent_path().empty() ? fs::path(".") : calib_txt.parent_path();
  std::vector<fs::path> images;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder / "image_0", ec)) {
    if (entry.path().extension() == ".png") images.push_back(entry.path());
  }
  if (images.empty()) {
    throw InputError(calib_txt.string() +
                     ": image size unknown: KITTI calib.txt has none and no image_0/*.png is beside it");
  }
  const GrayImage image = readPngGray(*std::min_element(images.begin(), images.end()));
  return {image.width(), image.height()};
}

}  // namespace

StereoRig loadKittiCalibration(const fs::path& calib_txt) {
  const std::string file = calib_txt.string();
  const std::map<std::string, Projection> projections = readProjections(calib_txt);
  StereoRig rig;
  rig.source = file;
  rig.body_frame = "cam0";
  const auto [width, height] = imageSize(calib_txt);
  for (const char* name : {"P0", "P1"}) {
    const auto it = projections.find(name);
    if (it == projections.end()) throw InputError(file + ": " + name + ": missing");
    const Mat34& p = it->second.matrix;
    const std::string where = file + ":" + std::to_string(it->second.line) + ": " + name;
    // Rectified: P = K [I | t] with K upper triangular, no skew and the last row (0 0 1 tz).
    const Eigen::Matrix3d k = p.leftCols<3>();
    if (k(1, 0) != 0.0 || k(2, 0) != 0.0 || k(2, 1) != 0.0 || k(0, 1) != 0.0 || k(2, 2) != 1.0) {
      throw InputError(where + ": expected a rectified projection K [I | t] (zero skew, last row 0 0 1 tz)");
    }
    const std::vector<double> params = {k(0, 0), k(1, 1), k(0, 2), k(1, 2)};
    GenericCamera<double> camera;
    try {
      camera = GenericCamera<double>::fromParams(PinholeCamera<double>::kName, params);
    } catch (const InputError& e) {
      throw InputError(where + ": " + e.what());
    }
    // x_i = K (X_cam0 + t_i): camera i sits at -t_i in the rectified cam0 frame. For P1,
    // t = (-b, 0, 0) with b > 0, so cam1 is b metres to the right (+x) of cam0.
    const Eigen::Vector3d t = k.inverse() * p.col(3);
    rig.cameras.push_back({camera, width, height, SE3d(SO3<double>(), -t)});
  }
  return rig;
}

}  // namespace voca
