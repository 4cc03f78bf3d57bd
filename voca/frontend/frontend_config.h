#pragma once
// Parameters of the KLT frontend (the JSON "frontend" section; defaults are the paper's EuRoC values).

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace voca {

// How initial guesses for temporal tracking are chosen and merged (DESIGN.md section 5).
enum class PriorMode : std::uint8_t {
  kNone,          // previous position only (the Basalt baseline)
  kMv,            // motion-vector prior only
  kOfThenMv,      // previous position; the failures retried with the MV prior
  kMvThenOf,      // MV prior; the failures retried from the previous position
  kMvParallelOf,  // both; kept when only one succeeds or both agree within consensus_tolerance
};

// The frames a frontend key acts on (presmooth, retry_previous_flow). Raw frames lack what decoded
// ones carry: the codec's smoothing and its motion vectors; some keys make up for that alone.
enum class InputScope : std::uint8_t {
  kOff,
  kRawInput,  // images that never passed through a video codec (datasets, cameras without encoding)
  kAlways,
};

// Whether a key of this scope acts on a frame that was (decoded) or was not decoded from video.
constexpr bool appliesTo(InputScope scope, bool decoded) {
  return scope == InputScope::kAlways || (scope == InputScope::kRawInput && !decoded);
}

// Where a new left point is first looked for in the right image.
enum class StereoGuess : std::uint8_t {
  kFixedDepth,    // reprojection at matching_default_depth_m
  kAverageDepth,  // reprojection at the backend's average depth (setAverageDepth), default until set
};

inline constexpr std::array<PriorMode, 5> kAllPriorModes = {PriorMode::kNone, PriorMode::kMv, PriorMode::kOfThenMv,
                                                            PriorMode::kMvThenOf, PriorMode::kMvParallelOf};

std::string_view priorModeName(PriorMode mode);
std::optional<PriorMode> parsePriorMode(std::string_view name);
// "none, mv, of_then_mv, mv_then_of or mv_parallel_of", for help texts and messages.
std::string priorModeList();
// parsePriorMode, or InputError "<what>: unknown mode "x" (expected none, mv, ...)".
PriorMode requirePriorMode(std::string_view name, std::string_view what);
std::string_view inputScopeName(InputScope scope);
// "off", "raw" or "always"; JSON true and false are read as "always" and "off" by the config reader.
std::optional<InputScope> parseInputScope(std::string_view name);
std::string_view stereoGuessName(StereoGuess guess);
std::optional<StereoGuess> parseStereoGuess(std::string_view name);

struct FrontendConfig {
  int grid_size_px = 40;
  int pyramid_levels = 3;  // levels above the full-resolution image (4 levels in all)
  int max_iterations = 5;  // Gauss-Newton iterations per level
  // A level's iterations also stop once a step moves the patch less than this (level pixels): on the
  // full-resolution level min_step_px, on the coarser ones, whose result the finer levels refine,
  // coarse_min_step_px. Larger values save iterations and move results slightly (configs/README.md).
  double min_step_px = 0.002;
  double coarse_min_step_px = 0.05;
  // Near the image border a coarse level's patch (the pattern at 2^level times its size) runs out of
  // image: skip that level's alignment, from where it started, instead of failing the track
  // (AlignParams::skip_coarse_outside). Off = Basalt's behaviour.
  bool skip_coarse_outside = false;
  int pattern = 52;                       // 24 or 52 sample points per patch
  double max_recovered_dist2_px2 = 0.25;  // forward-backward round trip tolerance
  // The same tolerance for the left-to-right match of a new point; 0 = max_recovered_dist2_px2 (Basalt
  // uses one for both). The two cameras are encoded as separate streams, each with its own
  // quantisation artefacts, so a correct stereo match returns less exactly than a temporal track
  // within one stream, whose P-frames carry the texture along the motion (configs/README.md).
  double stereo_max_recovered_dist2_px2 = 0.0;
  // The left-right match's tolerance in effect (squared px).
  double stereoRoundTripDist2() const {
    return stereo_max_recovered_dist2_px2 > 0.0 ? stereo_max_recovered_dist2_px2 : max_recovered_dist2_px2;
  }
  double epipolar_error = 0.005;  // |f0^T E f1| on unit bearings
  StereoGuess matching_guess = StereoGuess::kFixedDepth;
  double matching_default_depth_m = 2.0;
  double image_safe_radius_px = 0.0;  // detect only this close to the principal point; 0 = everywhere
  int detection_max_threshold = 40;
  int detection_min_threshold = 5;
  int detection_border_px = 19;
  PriorMode prior_mode = PriorMode::kMvParallelOf;
  double consensus_tolerance_px2 = 0.05;
  bool bridge_iframes = true;  // reuse the last P-frame's motion on I-frames
  // Codec confidence: which motion vectors the prior trusts. A distrusted vector is treated as
  // absent (the point is tracked as in mode none). All off by default.
  //  - prior_reject_inconsistent: vectors that deviate from their 24 px neighbourhood's median by
  //    more than max(2 px, half its length) (MotionField::flagOutliers): isolated wrong matches of
  //    the encoder's search, typical on blur and repetitive texture.
  //  - prior_min_block_px: vectors of partitions smaller than this side (area below its square);
  //    small partitions are where the encoder's rate-distortion choice tracked noise.
  //  - prior_max_residual_px: vectors whose motion-compensated prediction explains the point's 8x8
  //    neighbourhood poorly: mean absolute difference between the previous image at the point and
  //    the current image at the point plus the vector, over the neighbourhood's mean gradient, i.e.
  //    the vector's apparent misalignment in pixels (0 = off). The decoded images' stand-in for the
  //    residual energy the bitstream carries but FFmpeg does not export.
  //  - prior_max_qp: vectors of macroblocks quantised more coarsely than this (codec units: H.264 QP
  //    0..51; 0 = off): the encoder spent few bits there, so the block's prediction residual was
  //    left large and its vector is a cheap match rather than the true motion. Vectors without an
  //    exported quantiser are kept.
  bool prior_reject_inconsistent = false;
  int prior_min_block_px = 0;
  double prior_max_residual_px = 0.0;
  int prior_max_qp = 0;
  // Pyramid levels above full resolution on which a guess from a P-frame's motion vector is tracked
  // (forward and round trip); -1 = pyramid_levels. The vector usually lands within a pixel or two,
  // which the finest levels capture without the coarse ones. Bridged vectors (carried over an I-frame),
  // of_then_mv's rescue tracks and the plain guess from the previous position always use
  // pyramid_levels.
  int prior_pyramid_levels = -1;
  // Pyramid levels above full resolution on which the round-trip check of a track runs; -1 = those of
  // the forward track (Basalt). With fewer, the check skips the coarse levels: it starts where undoing
  // the forward track's coarse levels would put it, p plus what the forward track's finer levels
  // moved, and runs only the finer levels, so the coarse levels' work is done once per track, not
  // twice (configs/README.md, "Alignment effort").
  int backward_pyramid_levels = -1;
  // mv_parallel_of: a motion-vector guess that lands within this distance (level-0 pixels) of the
  // plain track's result, which passed its round trip, is taken as agreeing with it and not tracked.
  // Started that close to a minimum the prior track converges to the same one, so running it only
  // confirms; 0 = always track it (configs/README.md has the measurements).
  double prior_agree_radius_px = 0.0;
  // mv_parallel_of: a point the plain track lost is kept from the prior track alone (the paper's
  // rule, "tracked once is a success") only when its motion vector is at least this long (level-0
  // pixels; 0 = always, the paper). That prior track's round trip starts from the negated vector, so
  // a track that barely moved returns to its start whatever it matched: the check the paper itself
  // calls unreliable for vector-initialised tracks. A short vector started the plain track within
  // its reach, so there the plain failure says the point itself is bad (blur, occlusion); a long one
  // is motion the pyramid cannot bridge, what the prior is for. A huge value: the prior only vetoes.
  double prior_rescue_min_px = 0.0;
  // Also detect in the right image where the left camera does not see (cells whose reprojection
  // at matching_default_depth_m misses the left image); those tracks are right-only. TUM-VI's
  // official setting (optical_flow_detection_nonoverlap, from Monado's Basalt).
  bool detection_nonoverlap = false;
  // When the left camera's tracks fill the capacity (max_points) after the temporal step, so that no
  // point could be detected, the younger of two left tracks closer than this (level-0 pixels) is
  // dropped, in both cameras, to make room. Where the image flow converges (a forward flight's far
  // field, the camera backing away) no track leaves the image and tracks bunch onto the same
  // texture: near-duplicates that weigh one error twice, age without end and keep every fresh point
  // out. Basalt has no capacity, so it never gets here; 0 = never drop.
  double thin_when_full_px = 0.0;
  // A left track whose right partner was lost (or never found when it was detected) is matched to the
  // right image again in every frame, as a new point is. Basalt matches a track left to right only
  // when it is detected, so a track whose right view is lost once stays monocular for life.
  bool stereo_rematch = false;
  // A point every guess lost (the previous position, and the motion vector where the mode has one)
  // gets one more track, started where the camera's image flow of the previous frame would put it:
  // the median displacement of that frame's kept tracks. Plain KLT reaches only as far as its
  // coarsest level; when the camera moves faster than that (a low frame rate, a fast turn) every
  // point is lost at once and the estimator has nothing to work with. Flow shorter than a pixel is
  // not retried (that track would start where the plain one did). Before any step has measured the
  // flow (the first step of a run, or the first after KltFrontend::reset) the retry starts from the whole image's
  // shift, searched on the coarsest level (ImageShiftSearch). Not in Basalt or the paper.
  InputScope retry_previous_flow = InputScope::kOff;
  // The retry runs only in frames where the guesses lost at least this share of the previous frame's
  // points: a turn beyond the pyramid's reach loses most of them at once, an ordinary frame a few
  // (they left the view, were occluded or changed). Retrying the few as well raised raw MH_03's ATE
  // (configs/README.md). 0 = retry in every frame.
  double retry_min_lost_fraction = 0.0;
  // Smooth the full-resolution image by [1 2 1]/4 before tracking, against the sub-pixel bias the
  // patterns' 2 px sample grid has on sharp images and against sensor noise (see ImagePyramid).
  // kRawInput leaves decoded frames alone: the codec has smoothed them already, and smoothing them
  // again costs the prior modes accuracy (configs/README.md). Not in Basalt or the paper.
  InputScope presmooth = InputScope::kOff;
};

}  // namespace voca

namespace voca {

// Checks every value against its allowed range; throws InputError naming `context`.<key>, the
// allowed range and the value found (e.g. "config.json: frontend.pattern: expected 24 or 52, got 30").
void validateFrontendConfig(const FrontendConfig& config, const std::string& context = "frontend");

}  // namespace voca
