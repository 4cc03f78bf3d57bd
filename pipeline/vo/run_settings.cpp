#include "pipeline/vo/run_settings.h"

#include <fmt/core.h>

#include "voca/core/error.h"

namespace voca::pipeline {

void applyRunSettings(const RunSettings& settings, VoRunOptions& options) {
  if (settings.threads < 0) {
    throw InputError(fmt::format("--threads: expected auto or a positive count, got {}", settings.threads));
  }
  options.pipeline_options.threads = settings.threads;
  if (settings.frontend_threads < 0 || settings.frontend_threads > 2) {
    throw InputError(fmt::format("--frontend-threads: expected auto, 1 or 2, got {}", settings.frontend_threads));
  }
  options.frontend_camera_threads = settings.frontend_threads;
  options.pipeline_options.pins.clear();
  if (!settings.pins.empty()) options.pipeline_options.pins = parseStagePins(settings.pins);
  const auto scheduling = platform::parseSchedulingPolicy(settings.scheduling);
  if (!scheduling) {
    throw InputError(fmt::format("--sched: expected other, fifo or rr, got \"{}\"", settings.scheduling));
  }
  options.pipeline_options.scheduling = *scheduling;
  if (*scheduling != platform::SchedulingPolicy::kOther && (settings.priority < 1 || settings.priority > 99)) {
    throw InputError(fmt::format("--priority: expected 1 to 99, got {}", settings.priority));
  }
  options.pipeline_options.priority = settings.priority;
  options.pipeline_options.lock_memory = settings.lock_memory;
  // NaN paced nothing (every comparison false): the run waited forever at frame 0.
  if (!(settings.speed > 0.0 && settings.speed <= 1e6)) {
    throw InputError(fmt::format("--speed: expected a factor above 0 and at most 1e6, got {}", settings.speed));
  }
  options.realtime = settings.realtime;
  options.speed = settings.speed;
  options.strict = settings.strict;
  options.decoder = decode::parseDecoderKind(settings.decoder);
  options.skip_deblock = settings.skip_deblock;
  options.pipeline_options.trace_path = settings.trace_file;
  options.statistics_file = settings.statistics_file;
}

}  // namespace voca::pipeline
