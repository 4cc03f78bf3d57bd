#include "voca/frontend/frontend_config.h"

#include <fmt/core.h>
#include <cmath>

#include "voca/core/error.h"

namespace voca {

std::string_view priorModeName(PriorMode mode) {
  switch (mode) {
    case PriorMode::kNone:
      return "none";
    case PriorMode::kMv:
      return "mv";
    case PriorMode::kOfThenMv:
      return "of_then_mv";
    case PriorMode::kMvThenOf:
      return "mv_then_of";
    case PriorMode::kMvParallelOf:
      return "mv_parallel_of";
  }
  return "?";
}

std::optional<PriorMode> parsePriorMode(std::string_view name) {
  for (PriorMode mode : kAllPriorModes) {
    if (priorModeName(mode) == name) return mode;
  }
  return std::nullopt;
}

std::string priorModeList() {
  std::string list;
  for (std::size_t i = 0; i < kAllPriorModes.size(); ++i) {
    list += i == 0 ? "" : i + 1 == kAllPriorModes.size() ? " or " : ", ";
    list += priorModeName(kAllPriorModes[i]);
  }
  return list;
}

PriorMode requirePriorMode(std::string_view name, std::string_view what) {
  const std::optional<PriorMode> mode = parsePriorMode(name);
  if (!mode) throw InputError(fmt::format("{}: unknown mode \"{}\" (expected {})", what, name, priorModeList()));
  return *mode;
}

std::string_view inputScopeName(InputScope scope) {
  switch (scope) {
    case InputScope::kOff:
      return "off";
    case InputScope::kRawInput:
      return "raw";
    case InputScope::kAlways:
      return "always";
  }
  return "off";
}

std::optional<InputScope> parseInputScope(std::string_view name) {
  for (const InputScope scope : {InputScope::kOff, InputScope::kRawInput, InputScope::kAlways}) {
    if (name == inputScopeName(scope)) return scope;
  }
  return std::nullopt;
}

std::string_view stereoGuessName(StereoGuess guess) {
  return guess == StereoGuess::kFixedDepth ? "reproj_fixed_depth" : "reproj_avg_depth";
}

std::optional<StereoGuess> parseStereoGuess(std::string_view name) {
  if (name == "reproj_fixed_depth") return StereoGuess::kFixedDepth;
  if (name == "reproj_avg_depth") return StereoGuess::kAverageDepth;
  return std::nullopt;
}

namespace {

// hi_key: the key of the same section whose value is the upper bound, named in the message (a file
// that lowers that key can put another key's value out of range).
void checkInt(const std::string& context, const char* key, int value, int lo, int hi, const char* hi_key = nullptr) {
  if (value < lo || value > hi) {
    throw InputError(fmt::format("{}.{}: expected an integer in [{}, {}]{}, got {}", context, key, lo, hi,
                                 hi_key != nullptr ? fmt::format(" (at most {})", hi_key) : "", value));
  }
}

// lo_open: the lower bound itself is not allowed.
void checkReal(const std::string& context, const char* key, double value, double lo, double hi, bool lo_open) {
  const bool ok = std::isfinite(value) && (lo_open ? value > lo : value >= lo) && value <= hi;
  if (!ok) {
    throw InputError(
        fmt::format("{}.{}: expected a number in {}{}, {}], got {}", context, key, lo_open ? "(" : "[", lo, hi, value));
  }
}

}  // namespace

void validateFrontendConfig(const FrontendConfig& c, const std::string& context) {
  checkInt(context, "grid_size_px", c.grid_size_px, 8, 1024);
  checkInt(context, "pyramid_levels", c.pyramid_levels, 0, 6);
  checkInt(context, "max_iterations", c.max_iterations, 1, 100);
  checkReal(context, "min_step_px", c.min_step_px, 0.0, 10.0, true);
  checkReal(context, "coarse_min_step_px", c.coarse_min_step_px, 0.0, 10.0, true);
  if (c.pattern != 24 && c.pattern != 52) {
    throw InputError(fmt::format("{}.pattern: expected 24 or 52, got {}", context, c.pattern));
  }
  checkReal(context, "max_recovered_dist2_px2", c.max_recovered_dist2_px2, 0.0, 100.0, true);
  checkReal(context, "stereo_max_recovered_dist2_px2", c.stereo_max_recovered_dist2_px2, 0.0, 100.0, false);
  checkReal(context, "epipolar_error", c.epipolar_error, 0.0, 1.0, true);
  checkReal(context, "matching_default_depth_m", c.matching_default_depth_m, 0.0, 1e4, true);
  checkReal(context, "image_safe_radius_px", c.image_safe_radius_px, 0.0, 1e5, false);
  checkInt(context, "detection_max_threshold", c.detection_max_threshold, 1, 255);
  checkInt(context, "detection_min_threshold", c.detection_min_threshold, 1, c.detection_max_threshold,
           "detection_max_threshold");
  checkInt(context, "detection_border_px", c.detection_border_px, 3, 1000);
  checkReal(context, "consensus_tolerance_px2", c.consensus_tolerance_px2, 0.0, 1e4, false);
  checkInt(context, "prior_min_block_px", c.prior_min_block_px, 0, 64);
  checkReal(context, "prior_max_residual_px", c.prior_max_residual_px, 0.0, 1e3, false);
  checkInt(context, "prior_max_qp", c.prior_max_qp, 0, 127);  // H.264's 51, MPEG-2's non-linear scale 112
  checkInt(context, "prior_pyramid_levels", c.prior_pyramid_levels, -1, c.pyramid_levels, "pyramid_levels");
  checkInt(context, "backward_pyramid_levels", c.backward_pyramid_levels, -1, c.pyramid_levels, "pyramid_levels");
  checkReal(context, "prior_agree_radius_px", c.prior_agree_radius_px, 0.0, 100.0, false);
  checkReal(context, "thin_when_full_px", c.thin_when_full_px, 0.0, 1000.0, false);
  checkReal(context, "prior_rescue_min_px", c.prior_rescue_min_px, 0.0, 1e6, false);
  checkReal(context, "retry_min_lost_fraction", c.retry_min_lost_fraction, 0.0, 1.0, false);
}

}  // namespace voca
