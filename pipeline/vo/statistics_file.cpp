#include "pipeline/vo/statistics_file.h"

#include <fmt/core.h>

#include <nlohmann/json.hpp>

#include <fstream>

#include "formats/eval/eval_report_json.h"
#include "platform/realtime/clock.h"
#include "voca/core/error.h"

namespace voca::pipeline {

namespace {

nlohmann::json histogramJson(const LatencyHistogram& h) {
  return {{"count", h.count()},
          {"p50_ms", platform::nsToMs(h.quantileNs(0.5))},
          {"p90_ms", platform::nsToMs(h.quantileNs(0.9))},
          {"p99_ms", platform::nsToMs(h.quantileNs(0.99))},
          {"max_ms", platform::nsToMs(h.maxNs())},
          {"mean_ms", h.meanNs() * 1e-6}};
}

nlohmann::json distanceJson(const DistanceHistogram& h) {
  // Sparse: [bin start px, count] for the non-empty bins, the overflow bin as its start (16 px).
  nlohmann::json bins = nlohmann::json::array();
  for (int b = 0; b <= DistanceHistogram::kBins; ++b) {
    const std::int64_t count = h.bins()[static_cast<std::size_t>(b)];
    if (count > 0) bins.push_back({b * DistanceHistogram::kBinPx, count});
  }
  return {{"count", h.count()},
          {"median_px", h.quantile(0.5)},
          {"p90_px", h.quantile(0.9)},
          {"bin_px", DistanceHistogram::kBinPx},
          {"bins", bins}};
}

}  // namespace

void writeStatisticsJson(const VoRunResult& r, const std::filesystem::path& file) {
  nlohmann::json j;
  j["input"] = r.description;
  j["config"] = r.config_name;
  j["mode"] = std::string(priorModeName(r.config.frontend.prior_mode));
  j["bridge_iframes"] = r.config.frontend.bridge_iframes;
  j["has_motion"] = r.has_motion;
  j["decoder"] = r.decoder_description;
  j["image_size"] = {r.width, r.height};
  j["frames"] = r.frames;
  j["stopped_by_signal"] = r.stop_signal;
  j["source_ended"] = r.source_end;  // live input: why it ended; the counters are under "pipeline"
  const RunReport& p = r.pipeline_report;
  if (p.error) {
    j["error"] = {{"stage", p.error->stage}, {"frame", p.error->frame_index}, {"message", p.error->message}};
  }
  j["backend"] = {{"keyframes", r.backend.keyframes}, {"resets", r.backend.resets}, {"lost", r.backend.lost}};
  const FrontendTotals& t = r.frontend;
  j["frontend"] = {{"temporal_tracks", t.previous},
                   {"kept", t.kept},
                   {"rescued_by_prior", t.rescued},
                   {"consensus_rejections", t.consensus},
                   {"tracked_from_previous", t.tracked_plain},
                   {"tracked_from_prior", t.tracked_prior},
                   {"with_vector", t.with_vector},
                   {"distrusted_vectors", t.distrusted},
                   {"prior_tracks_confirmed", t.prior_confirmed},
                   {"flow_retried", t.flow_retried},
                   {"flow_searched", t.flow_searched},
                   {"detected", t.detected},
                   {"detected_right_only", t.detected_right_only},
                   {"thinned", t.thinned},
                   {"stereo_matched", t.stereo_matched},
                   {"stereo_rematched", t.stereo_rematched},
                   {"epipolar_rejections", t.epipolar},
                   {"bridged_frames", t.bridged_frames},
                   {"left_points", t.left_points},
                   {"right_points", t.right_points},
                   {"guess_distance_previous", distanceJson(t.guess_plain)},
                   {"guess_distance_prior", distanceJson(t.guess_prior)}};
  nlohmann::json stages = nlohmann::json::array();
  for (const StageReport& s : p.stages) {
    nlohmann::json stage = {{"name", s.name},
                            {"thread", s.thread},
                            {"core", s.core},
                            {"service", histogramJson(s.service)},
                            {"wait", histogramJson(s.wait)},
                            {"cpu", histogramJson(s.cpu)},
                            {"queue_high_water", s.queue_high_water},
                            {"dropped", s.dropped},
                            {"damaged", s.damaged}};
    if (s.helper_service.count() > 0) {
      stage["helper"] = {
          {"core", s.helper_core}, {"service", histogramJson(s.helper_service)}, {"cpu", histogramJson(s.helper_cpu)}};
    }
    stages.push_back(stage);
  }
  nlohmann::json released = nlohmann::json::array();
  for (const ReleasedFrame& f : p.released) {
    if (f.reason == ReleaseReason::kDropped || f.reason == ReleaseReason::kDamaged) {
      released.push_back({{"frame", f.frame_index},
                          {"stage", p.stages[static_cast<std::size_t>(f.stage)].name},
                          {"reason", f.reason == ReleaseReason::kDropped ? "dropped" : "damaged"}});
    }
  }
  j["pipeline"] = {{"threads", p.threads},
                   {"frontend_camera_threads", r.frontend_camera_threads},
                   {"wall_s", p.wall_s},
                   {"frames_per_s", p.wall_s > 0 ? static_cast<double>(p.completed) / p.wall_s : 0.0},
                   {"produced", p.produced},
                   {"source_frames_lost", r.source.frames_lost},
                   {"source_unpaired", r.source.unpaired},
                   {"completed", p.completed},
                   {"dropped", p.dropped},
                   {"damaged", p.damaged},
                   {"skipped_frames", released},
                   {"end_to_end", histogramJson(p.end_to_end)},
                   {"stages", stages}};
  if (r.eval) {
    j["eval"] = evalReportToJson(*r.eval, EvalOptions{});
    j["ground_truth"] = r.ground_truth;
  }
  nlohmann::json rows = nlohmann::json::array();
  for (const FrameRecord& f : r.rows) {
    rows.push_back({f.frame_index,
                    f.t_ns,
                    f.missing_before,
                    std::string(1, f.picture_type),
                    f.bridged,
                    f.left,
                    f.right,
                    f.kept,
                    f.lost,
                    f.rescued,
                    f.consensus_rejections,
                    f.detected,
                    std::string(trackingStateName(static_cast<TrackingState>(f.state))),
                    f.keyframe,
                    f.landmarks,
                    f.inliers,
                    f.decode_ms,
                    f.frontend_ms,
                    f.backend_ms,
                    f.frontend_cpu_ms,
                    f.backend_cpu_ms});
  }
  j["frame_columns"] = {"frame",
                        "t_ns",
                        "missing_before",
                        "picture",
                        "bridged",
                        "left",
                        "right",
                        "kept",
                        "lost",
                        "rescued",
                        "consensus_rejections",
                        "detected",
                        "state",
                        "keyframe",
                        "landmarks",
                        "inliers",
                        "decode_ms",
                        "frontend_ms",
                        "backend_ms",
                        "frontend_cpu_ms",
                        "backend_cpu_ms"};
  j["frame_rows"] = rows;
  j["frame_rows_truncated"] = r.frames > static_cast<std::int64_t>(r.rows.size());
  std::ofstream file_out(file);
  file_out << j.dump(1) << "\n";
  if (!file_out) throw InputError(fmt::format("cannot write statistics file {}", file.string()));
}

}  // namespace voca::pipeline
