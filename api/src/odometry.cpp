#include "voca_rt/odometry.h"

#include <fmt/core.h>

#include <atomic>
#include <exception>
#include <thread>

#include "api/src/api_internal.h"
#include "drivers/encode/video_encoder.h"
#include "drivers/source/push_source.h"
#include "formats/trajectory/trajectory_writer.h"
#include "pipeline/vo/output_checks.h"
#include "pipeline/vo/statistics_file.h"
#include "pipeline/vo/vo_session.h"
#include "voca_rt/version.h"

namespace voca_rt {

namespace pl = voca::pipeline;

const char* version() { return VOCA_RT_VERSION; }

std::array<double, 16> Pose::matrix() const {
  const Eigen::Quaterniond q(orientation[3], orientation[0], orientation[1], orientation[2]);
  const Eigen::Matrix3d r = q.toRotationMatrix();
  std::array<double, 16> m{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m[static_cast<std::size_t>(4 * i + j)] = r(i, j);
    m[static_cast<std::size_t>(4 * i + 3)] = position[static_cast<std::size_t>(i)];
  }
  m[15] = 1.0;
  return m;
}

std::string tumRow(const Pose& pose) {
  // The parts as they are (no SE3 in between, which would renormalise the quaternion), so the row is
  // byte for byte the one the trajectory writer wrote for the same estimate.
  const Eigen::Quaterniond q(pose.orientation[3], pose.orientation[0], pose.orientation[1], pose.orientation[2]);
  fmt::memory_buffer row;
  voca::formatTumRow(pose.t_ns, Eigen::Vector3d(pose.position[0], pose.position[1], pose.position[2]), q, row);
  return std::string(row.data(), row.size());
}

struct Odometry::Impl {
  Options options;
  Stop on_destroy = Stop::kFlush;
  std::unique_ptr<voca::PushSource> source;
  std::unique_ptr<detail::PoseSink> sink;
  std::unique_ptr<pl::VoSession> session;
  std::filesystem::path statistics_file;
  std::string description;
  std::thread thread;
  // Set by the pipeline's thread when it has ended; the result and summary are its until then.
  std::atomic<bool> done{false};
  pl::VoRunResult result;
  Summary summary;
  std::exception_ptr failure;
  bool finished = false;

  void runPipeline() {
    try {
      session->run();
      result = session->takeResult();
      summary = detail::summary(result);
    } catch (...) {
      failure = std::current_exception();
    }
    done.store(true, std::memory_order_release);
  }

  // Throws when the pipeline has ended before the input did: a stage failed, or a stop request.
  void requireRunning() {
    if (finished) throw Error(Error::Kind::kInput, "the odometry has finished: no frame can be pushed after finish()");
    if (!done.load(std::memory_order_acquire) && !session->failed()) return;
    if (thread.joinable()) thread.join();
    if (failure) detail::translated([&]() -> int { std::rethrow_exception(failure); });
    const std::string why = !summary.error.empty() ? summary.error
                            : summary.stopped      ? "a stop was requested"
                                                   : "the pipeline ended";
    throw Error(Error::Kind::kInput, fmt::format("the odometry has stopped: {}", why));
  }
};

Odometry::Odometry(const Options& options, PoseCallback on_pose, Stop on_destroy) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.options = options;
  d.on_destroy = on_destroy;
  detail::translated([&] {
    pl::VoRunOptions run = detail::runOptions(options);
    const voca::StereoRig rig = detail::stereoRig(options);
    rig.requireStereo();
    const pl::RunConfig config = pl::resolveRunConfig(
        options.config.empty() ? std::nullopt : std::optional<std::filesystem::path>(options.config));
    std::optional<std::filesystem::path> calibration_file;
    if (options.calibration.cameras.empty()) calibration_file = options.calibration_file;
    pl::requireOutputsApartFromInputs(run, nullptr, calibration_file);
    if (!options.encode_bitrate.empty()) {
      if (options.input != InputKind::kGray) {
        throw voca::InputError("encode_bitrate: the on-device encoder takes gray images (Options::input kGray)");
      }
      voca::encode::LiveEncoderSettings encoder;
      encoder.kind = voca::encode::parseEncoderKind(options.encoder);
      encoder.bitrate_bps = voca::encode::parseBitrate(options.encode_bitrate);
      voca::encode::setFrameRate(encoder, options.frame_rate_hz > 0.0 ? options.frame_rate_hz : 20.0);
      run.live_encode = encoder;
    }
    if (options.frame_rate_hz < 0.0) {
      throw voca::InputError(
          fmt::format("frame_rate_hz: expected a rate above 0 (or 0: unknown), got {}", options.frame_rate_hz));
    }
    if (!options.estimate) throw voca::InputError("estimate: an odometry pushes frames to get poses; it must estimate");
    run.keep_trajectory = false;  // the poses go to the program; no evaluation without ground truth
    run.pipeline_options.live_policy = options.live;
    d.statistics_file = run.statistics_file;

    voca::PushSourceOptions push;
    push.kind = options.input == InputKind::kH264 ? voca::SourceKind::kEncoded : voca::SourceKind::kRaw;
    push.width = rig.cameras[0].width;
    push.height = rig.cameras[0].height;
    push.live = options.live;
    push.nominal_rate_hz = options.frame_rate_hz;
    d.source = std::make_unique<voca::PushSource>(push);
    d.sink = std::make_unique<detail::PoseSink>(std::move(on_pose), options.poll_capacity);
    run.extra_sinks = {d.sink.get()};
    d.session = std::make_unique<pl::VoSession>(*d.source, rig, config.config, run);
    d.description = fmt::format(
        "config: {}, mode: {}{}", config.name, voca::priorModeName(d.session->config().frontend.prior_mode),
        d.session->decoderDescription().empty() ? std::string() : fmt::format(", {}", d.session->decoderDescription()));
    return 0;
  });
  d.thread = std::thread([&d] { d.runPipeline(); });
}

Odometry::~Odometry() {
  try {
    finish(impl_->on_destroy);
  } catch (...) {
    // A destructor must not throw; finish() reports the same to a caller who asks.
  }
}

bool Odometry::pushH264(std::int64_t t_ns, const std::uint8_t* left, std::size_t left_size, const std::uint8_t* right,
                        std::size_t right_size) {
  Impl& d = *impl_;
  if (d.options.input != InputKind::kH264) {
    throw Error(Error::Kind::kInput, "pushH264: this odometry takes gray images (Options::input kGray); use pushGray");
  }
  d.requireRunning();
  const bool taken = detail::translated([&] {
    return d.source->pushEncoded(t_ns, {left, left == nullptr ? 0 : left_size},
                                 {right, right == nullptr ? 0 : right_size});
  });
  if (!taken && !d.options.live) d.requireRunning();
  return taken;
}

bool Odometry::pushGray(std::int64_t t_ns, const std::uint8_t* left, const std::uint8_t* right, int width, int height,
                        int stride) {
  Impl& d = *impl_;
  if (d.options.input != InputKind::kGray) {
    throw Error(Error::Kind::kInput,
                "pushGray: this odometry takes H.264 access units (Options::input kH264); use pushH264");
  }
  d.requireRunning();
  const int row = stride > 0 ? stride : width;
  const bool taken = detail::translated([&] {
    return d.source->pushRaw(t_ns, {voca::ImageView<const std::uint8_t>{left, width, height, row},
                                    voca::ImageView<const std::uint8_t>{right, width, height, row}});
  });
  if (!taken && !d.options.live) d.requireRunning();
  return taken;
}

bool Odometry::poll(Pose& pose) { return impl_->sink->poll(pose); }

Summary Odometry::finish(Stop how) {
  Impl& d = *impl_;
  if (d.finished) return d.summary;
  if (how == Stop::kDiscard) {
    d.source->discardWaiting();
    d.session->requestStop();
  }
  d.source->close();
  if (d.thread.joinable()) d.thread.join();
  d.finished = true;
  if (d.failure) detail::translated([&]() -> int { std::rethrow_exception(d.failure); });
  if (!d.statistics_file.empty()) {
    detail::translated([&] {
      pl::writeStatisticsJson(d.result, d.statistics_file);
      return 0;
    });
  }
  return d.summary;
}

bool Odometry::running() const { return !impl_->done.load(std::memory_order_acquire); }

std::string Odometry::error() const {
  if (!impl_->done.load(std::memory_order_acquire)) return {};
  return impl_->summary.error;
}

std::string Odometry::description() const { return impl_->description; }

}  // namespace voca_rt
