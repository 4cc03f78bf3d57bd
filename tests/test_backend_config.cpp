// The backend's config section: shipped files carry the paper's values, and malformed sections are
// rejected with the key named (bad-input test, also run under AddressSanitizer).

#include <doctest/doctest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "formats/config/config.h"
#include "voca/core/error.h"

using namespace voca;

namespace {
std::string errorOf(const nlohmann::json& section) {
  try {
    parseBackendConfig(section, "test.json: backend");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("backend config: defaults are the paper's EuRoC values (Basalt config.vio_*)") {
  const BackendConfig c;
  CHECK(c.max_keyframes == 7);
  CHECK(c.min_frames_after_kf == 1);
  CHECK(c.new_kf_keypoints_thresh == 0.8);
  CHECK(c.kf_marg_feature_ratio == 0.2);
  CHECK_FALSE(c.rehost_landmarks);  // landmarks leave with their host keyframe, as in Basalt
  CHECK(c.obs_std_dev_px == 0.5);
  CHECK(c.obs_huber_thresh_px == 1.0);
  CHECK(c.min_triangulation_dist_m == 0.05);
  CHECK(c.outlier_threshold_px == 3.0);
  CHECK(c.filter_iteration == 4);
  CHECK(c.max_iterations == 7);
  CHECK(c.lm_lambda_initial == 1e-4);
  CHECK(c.lm_lambda_min == 1e-5);
  CHECK(c.lm_lambda_max == 1e2);
  CHECK(c.init_pose_weight == 1e8);
  CHECK_NOTHROW(validateBackendConfig(c));
}

TEST_CASE("backend config: shipped files parse, TUM-VI uses Gauss-Newton as the official config") {
  const std::string root = VOCA_SOURCE_DIR;
  const VocaConfig euroc = loadConfig(root + "/configs/euroc_vo.json");
  CHECK(euroc.backend.use_lm);
  CHECK(euroc.backend.lm_lambda_initial == 1e-4);
  CHECK(euroc.backend.max_keyframes == 7);
  const VocaConfig tumvi = loadConfig(root + "/configs/tumvi_vo.json");
  CHECK_FALSE(tumvi.backend.use_lm);
  CHECK(tumvi.backend.lm_lambda_initial == 1e-7);
  // Marginalising tracked landmarks with their host won on the EuRoC and TUM-VI motions, re-hosting
  // them on the KITTI clip (configs/README.md).
  CHECK_FALSE(euroc.backend.rehost_landmarks);
  CHECK_FALSE(tumvi.backend.rehost_landmarks);
  CHECK(loadConfig(root + "/configs/kitti_vo.json").backend.rehost_landmarks);
}

TEST_CASE("backend config: bad sections name the key and what was expected") {
  using nlohmann::json;
  CHECK(errorOf(json::parse(R"({"max_keyframes": 5, "min_inliers": 20})")).empty());
  CHECK(errorOf(json::parse(R"({"max_keyframe": 5})")).find("backend.max_keyframe: unknown key") != std::string::npos);
  CHECK(errorOf(json::parse(R"({"max_keyframes": 12})")).find("backend.max_keyframes: expected a value in [2, 9]") !=
        std::string::npos);
  CHECK(errorOf(json::parse(R"({"max_keyframes": 2.5})")).find("backend.max_keyframes: expected an integer") !=
        std::string::npos);
  CHECK(errorOf(json::parse(R"({"obs_std_dev_px": "0.5"})")).find("backend.obs_std_dev_px: expected a number") !=
        std::string::npos);
  CHECK(errorOf(json::parse(R"({"obs_std_dev_px": -1})")).find("backend.obs_std_dev_px") != std::string::npos);
  CHECK(errorOf(json::parse(R"({"use_lm": 1})")).find("backend.use_lm: expected true or false") != std::string::npos);
  CHECK(errorOf(json::parse(R"({"lm_lambda_min": 10, "lm_lambda_max": 1})")).find("backend.lm_lambda_min") !=
        std::string::npos);
  CHECK(errorOf(json::parse(R"([1, 2])")).find("expected a JSON object") != std::string::npos);
  // Through the whole-file loader the file name prefixes the key.
  try {
    parseConfig(json::parse(R"({"backend": {"outlier_threshold_px": 0}})"), "x.json");
    FAIL("expected InputError");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("x.json: backend.outlier_threshold_px") != std::string::npos);
  }
}
