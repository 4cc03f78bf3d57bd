#include "drivers/capture/libcamera_source.h"

#include <fmt/core.h>
#include <linux/videodev2.h>
#include <sys/mman.h>

#include <libcamera/libcamera.h>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <mutex>

#include "drivers/capture/pixel_format.h"
#include "drivers/capture/stereo_pairing.h"
#include "platform/realtime/clock.h"
#include "voca/core/error.h"

namespace voca::capture {

namespace lc = libcamera;

namespace {

constexpr int kMaxRequests = 16;

std::unique_ptr<lc::CameraManager> startManager() {
  // libcamera logs its version and missing IPA modules at INFO/WARN on every start; keep errors only
  // unless the user asked for more (libcamera reads this when its logger starts).
  setenv("LIBCAMERA_LOG_LEVELS", "*:ERROR", /*overwrite=*/0);
  auto manager = std::make_unique<lc::CameraManager>();
  if (const int r = manager->start(); r != 0) {
    throw RuntimeFailure(fmt::format("libcamera: the camera manager did not start ({})", std::strerror(-r)));
  }
  return manager;
}

std::string modelOf(const lc::Camera& camera) {
  const auto model = camera.properties().get(lc::properties::Model);
  return model ? *model : std::string("unknown model");
}

// The formats whose first plane is 8-bit luma, in order of preference.
bool lumaFirst(const lc::PixelFormat& format) {
  return format == lc::formats::R8 || format == lc::formats::YUV420 || format == lc::formats::NV12;
}

}  // namespace

std::vector<LibcameraCameraInfo> listLibcameraCameras() {
  const std::unique_ptr<lc::CameraManager> manager = startManager();
  std::vector<LibcameraCameraInfo> cameras;
  for (const std::shared_ptr<lc::Camera>& camera : manager->cameras())
    cameras.push_back({camera->id(), modelOf(*camera)});
  manager->stop();
  return cameras;
}

struct LibcameraStereoSource::Impl {
  struct Camera {
    std::shared_ptr<lc::Camera> camera;
    std::unique_ptr<lc::CameraConfiguration> config;
    lc::Stream* stream = nullptr;
    std::unique_ptr<lc::FrameBufferAllocator> allocator;
    std::vector<std::unique_ptr<lc::Request>> requests;
    std::vector<std::pair<void*, std::size_t>> mappings;  // one per buffer (cookie = index)
    std::vector<const std::uint8_t*> luma;                // the first plane of each buffer
    std::array<lc::Request*, kMaxRequests> completed{};   // filled by libcamera's thread, oldest first
    int num_completed = 0;
    bool acquired = false, started = false;
    bool have_sequence = false;
    unsigned last_sequence = 0;
    std::int64_t lost = 0;
    std::string name;
    Impl* owner = nullptr;

    void onCompleted(lc::Request* request) {
      if (request->status() == lc::Request::RequestCancelled) return;
      {
        std::lock_guard lock(owner->mutex);
        if (num_completed < kMaxRequests) completed[static_cast<std::size_t>(num_completed++)] = request;
      }
      owner->ready.notify_one();
    }
  };

  LibcameraStereoOptions options;
  std::unique_ptr<lc::CameraManager> manager;
  std::vector<std::unique_ptr<Camera>> cameras;
  SourceInfo info;
  std::int64_t tolerance_ns = 0;
  std::mutex mutex;
  std::condition_variable ready;
  std::array<lc::Request*, 2> pending{};
  bool started = false;
  std::atomic<bool> interrupted{false};
  std::atomic<std::int64_t> unpaired{0}, lost{0};
  std::int64_t delivered = 0;
  bool have_first = false;
  unsigned first_sequence = 0;

  std::shared_ptr<lc::Camera> find(const std::string& wanted) {
    const std::vector<std::shared_ptr<lc::Camera>> all = manager->cameras();
    for (std::size_t i = 0; i < all.size(); ++i) {
      if (wanted == all[i]->id() || wanted == std::to_string(i)) return all[i];
    }
    std::string available;
    for (std::size_t i = 0; i < all.size(); ++i) {
      available += fmt::format("{}{} ({}, {})", available.empty() ? "" : ", ", i, modelOf(*all[i]), all[i]->id());
    }
    throw InputError(fmt::format("libcamera camera {}: no such camera; available: {}", wanted,
                                 available.empty() ? "none found" : available));
  }

  void open(Camera& cam, const std::string& wanted) {
    cam.owner = this;
    cam.camera = find(wanted);
    cam.name = fmt::format("libcamera {} ({})", wanted, modelOf(*cam.camera));
    if (cam.camera->acquire() != 0) throw InputError(fmt::format("{}: busy (another program is using it)", cam.name));
    cam.acquired = true;
    cam.config = cam.camera->generateConfiguration({lc::StreamRole::VideoRecording});
    if (!cam.config || cam.config->empty()) throw RuntimeFailure(fmt::format("{}: no video configuration", cam.name));
    lc::StreamConfiguration& stream = cam.config->at(0);
    for (const lc::PixelFormat& format : {lc::formats::R8, lc::formats::YUV420, lc::formats::NV12}) {
      const std::vector<lc::PixelFormat> offered = stream.formats().pixelformats();
      if (std::find(offered.begin(), offered.end(), format) != offered.end()) {
        stream.pixelFormat = format;
        break;
      }
    }
    if (options.width > 0) stream.size = {static_cast<unsigned>(options.width), static_cast<unsigned>(options.height)};
    stream.bufferCount = static_cast<unsigned>(std::max(options.buffers, 2));
    if (cam.config->validate() == lc::CameraConfiguration::Invalid) {
      throw InputError(fmt::format("{}: cannot be configured for {}", cam.name, stream.toString()));
    }
    if (options.width > 0 && (static_cast<int>(stream.size.width) != options.width ||
                              static_cast<int>(stream.size.height) != options.height)) {
      throw InputError(fmt::format("{}: does not deliver {}x{} (nearest: {})", cam.name, options.width, options.height,
                                   stream.size.toString()));
    }
    if (!lumaFirst(stream.pixelFormat)) {
      throw InputError(fmt::format("{}: delivers {}, not a format with a luma plane (R8, YUV420, NV12)", cam.name,
                                   stream.pixelFormat.toString()));
    }
    if (cam.camera->configure(cam.config.get()) != 0)
      throw RuntimeFailure(fmt::format("{}: configure failed", cam.name));
    cam.stream = stream.stream();
    cam.allocator = std::make_unique<lc::FrameBufferAllocator>(cam.camera);
    if (cam.allocator->allocate(cam.stream) < 0)
      throw RuntimeFailure(fmt::format("{}: cannot allocate buffers", cam.name));
    const auto& buffers = cam.allocator->buffers(cam.stream);
    for (std::size_t i = 0; i < buffers.size(); ++i) {
      const lc::FrameBuffer::Plane& plane = buffers[i]->planes()[0];
      const std::size_t length = plane.offset + plane.length;
      void* address = ::mmap(nullptr, length, PROT_READ, MAP_SHARED, plane.fd.get(), 0);
      if (address == MAP_FAILED) throw RuntimeFailure(fmt::format("{}: cannot map buffer {}", cam.name, i));
      cam.mappings.emplace_back(address, length);
      cam.luma.push_back(static_cast<const std::uint8_t*>(address) + plane.offset);
      buffers[i]->setCookie(i);
      std::unique_ptr<lc::Request> request = cam.camera->createRequest(i);
      if (!request || request->addBuffer(cam.stream, buffers[i].get()) != 0) {
        throw RuntimeFailure(fmt::format("{}: cannot create request {}", cam.name, i));
      }
      cam.requests.push_back(std::move(request));
    }
    cam.camera->requestCompleted.connect(&cam, &Camera::onCompleted);
  }

  void start(Camera& cam) {
    lc::ControlList controls(lc::controls::controls);
    const lc::ControlInfoMap& supported = cam.camera->controls();
    if (options.rate_hz > 0.0 && supported.count(&lc::controls::FrameDurationLimits) > 0) {
      const auto frame_us = static_cast<std::int64_t>(std::llround(1e6 / options.rate_hz));
      const std::int64_t limits[2] = {frame_us, frame_us};
      controls.set(lc::controls::FrameDurationLimits, lc::Span<const std::int64_t, 2>(limits));
    }
    if (options.controls.exposure) {
      if (supported.count(&lc::controls::ExposureTime) == 0) throw InputError(cam.name + ": has no exposure control");
      controls.set(lc::controls::AeEnable, false);
      controls.set(lc::controls::ExposureTime, static_cast<std::int32_t>(*options.controls.exposure));
    }
    if (options.controls.gain) {
      if (supported.count(&lc::controls::AnalogueGain) == 0) throw InputError(cam.name + ": has no gain control");
      controls.set(lc::controls::AnalogueGain, static_cast<float>(*options.controls.gain));
    }
    if (cam.camera->start(&controls) != 0) throw RuntimeFailure(fmt::format("{}: start failed", cam.name));
    cam.started = true;
    for (const auto& request : cam.requests) {
      if (cam.camera->queueRequest(request.get()) != 0) throw RuntimeFailure(cam.name + ": cannot queue a request");
    }
  }

  void requeue(Camera& cam, lc::Request* request) {
    request->reuse(lc::Request::ReuseBuffers);
    if (cam.camera->queueRequest(request) != 0) {
      throw RuntimeFailure(fmt::format("{}: cannot queue a request (camera disconnected?)", cam.name));
    }
  }

  void close(Camera& cam) {
    if (cam.started) cam.camera->stop();
    if (cam.camera) cam.camera->requestCompleted.disconnect(&cam, &Camera::onCompleted);
    cam.requests.clear();
    for (const auto& [address, length] : cam.mappings) ::munmap(address, length);
    if (cam.allocator && cam.stream) cam.allocator->free(cam.stream);
    cam.allocator.reset();
    if (cam.acquired) cam.camera->release();
    cam.camera.reset();
  }
};

LibcameraStereoSource::LibcameraStereoSource(const LibcameraStereoOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.options = options;
  if (options.cameras.empty() || options.cameras.size() > 2) {
    throw InputError("libcamera: expected one side-by-side camera or two cameras (left, right)");
  }
  d.manager = startManager();
  try {
    for (const std::string& wanted : options.cameras) {
      d.cameras.push_back(std::make_unique<Impl::Camera>());
      d.open(*d.cameras.back(), wanted);
    }
    const lc::StreamConfiguration& left = d.cameras[0]->config->at(0);
    const auto width = static_cast<int>(left.size.width), height = static_cast<int>(left.size.height);
    if (d.cameras.size() == 2) {
      const lc::StreamConfiguration& right = d.cameras[1]->config->at(0);
      if (right.size != left.size) {
        throw InputError(fmt::format("{} delivers {} but {} delivers {}; the stereo cameras must match",
                                     d.cameras[0]->name, left.size.toString(), d.cameras[1]->name,
                                     right.size.toString()));
      }
      d.info.width = width;
      d.info.height = height;
      d.info.description = fmt::format("stereo cameras {} + {}, {}x{} {}", d.cameras[0]->name, d.cameras[1]->name,
                                       width, height, left.pixelFormat.toString());
    } else {
      if (width % 2 != 0) throw InputError(fmt::format("{}: side-by-side needs an even width", d.cameras[0]->name));
      d.info.width = width / 2;
      d.info.height = height;
      d.info.description =
          fmt::format("side-by-side stereo camera {}, split into 2x {}x{}", d.cameras[0]->name, d.info.width, height);
    }
  } catch (...) {
    for (auto& cam : d.cameras) d.close(*cam);
    d.cameras.clear();
    d.manager->stop();
    throw;
  }
  d.info.kind = SourceKind::kRaw;
  d.info.live = true;
  d.info.nominal_rate_hz = options.rate_hz;
  d.tolerance_ns = options.pair_tolerance_ns > 0 ? options.pair_tolerance_ns : defaultPairTolerance(options.rate_hz);
}

LibcameraStereoSource::~LibcameraStereoSource() {
  for (auto& cam : impl_->cameras) impl_->close(*cam);
  impl_->cameras.clear();
  if (impl_->manager) impl_->manager->stop();
}

const SourceInfo& LibcameraStereoSource::info() const { return impl_->info; }
void LibcameraStereoSource::interrupt() {
  impl_->interrupted = true;
  impl_->ready.notify_all();
}
SourceCounters LibcameraStereoSource::counters() const {
  return {.frames_lost = impl_->lost.load(), .unpaired = impl_->unpaired.load()};
}

bool LibcameraStereoSource::next(RawStereoFrame& frame) {
  Impl& d = *impl_;
  if (d.interrupted || (d.options.max_frames > 0 && d.delivered >= d.options.max_frames)) return false;
  if (!d.started) {
    for (auto& cam : d.cameras) d.start(*cam);
    d.started = true;
  }
  const std::size_t n = d.cameras.size();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(d.options.frame_timeout_ms);
  while (!d.interrupted) {
    // Take the oldest completed request of every camera that has none pending.
    bool all = true;
    {
      std::unique_lock lock(d.mutex);
      for (std::size_t c = 0; c < n; ++c) {
        Impl::Camera& cam = *d.cameras[c];
        if (d.pending[c] == nullptr && cam.num_completed > 0) {
          d.pending[c] = cam.completed[0];
          std::copy(cam.completed.begin() + 1, cam.completed.begin() + cam.num_completed, cam.completed.begin());
          --cam.num_completed;
        }
        all = all && d.pending[c] != nullptr;
      }
      if (!all) {
        if (d.ready.wait_until(lock, deadline) == std::cv_status::timeout) {
          throw RuntimeFailure(fmt::format("libcamera: no stereo frame for {} ms (camera stalled or disconnected?)",
                                           d.options.frame_timeout_ms));
        }
        continue;
      }
    }
    // Damaged frames go back to the camera and count as lost; sequence gaps count too.
    std::array<std::int64_t, 2> t_ns{};
    bool damaged = false;
    for (std::size_t c = 0; c < n; ++c) {
      Impl::Camera& cam = *d.cameras[c];
      const lc::FrameBuffer* buffer = d.pending[c]->findBuffer(cam.stream);
      const lc::FrameMetadata& metadata = buffer->metadata();
      if (cam.have_sequence && metadata.sequence != cam.last_sequence + 1) {
        cam.lost += metadata.sequence - cam.last_sequence - 1;
      }
      cam.have_sequence = true;
      cam.last_sequence = metadata.sequence;
      t_ns[c] = static_cast<std::int64_t>(metadata.timestamp);
      if (metadata.status != lc::FrameMetadata::FrameSuccess) {
        ++cam.lost;
        d.requeue(cam, d.pending[c]);
        d.pending[c] = nullptr;
        damaged = true;
      }
    }
    if (damaged) continue;
    if (n == 2) {
      const PairDecision decision = decidePair(t_ns[0], t_ns[1], d.tolerance_ns);
      if (decision != PairDecision::kPair) {
        const std::size_t older = decision == PairDecision::kDropLeft ? 0 : 1;
        d.requeue(*d.cameras[older], d.pending[older]);
        d.pending[older] = nullptr;
        d.unpaired.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
    }
    for (std::size_t c = 0; c < 2; ++c) {
      const std::size_t source = n == 2 ? c : 0;
      Impl::Camera& cam = *d.cameras[source];
      const lc::StreamConfiguration& stream = cam.config->at(0);
      const lc::FrameBuffer* buffer = d.pending[source]->findBuffer(cam.stream);
      const std::size_t bytes = buffer->metadata().planes()[0].bytesused;
      const int x0 = n == 2 ? 0 : static_cast<int>(c) * d.info.width;
      convertToGray(cam.luma[buffer->cookie()], bytes, V4L2_PIX_FMT_GREY, stream.stride, x0, d.info.width,
                    d.info.height, frame.images[c]);
    }
    frame.t_ns = t_ns[0];
    const unsigned sequence = d.cameras[0]->last_sequence;
    if (!d.have_first) {
      d.have_first = true;
      d.first_sequence = sequence;
    }
    frame.frame_index = static_cast<std::int64_t>(sequence - d.first_sequence);
    std::int64_t lost = 0;
    for (std::size_t c = 0; c < n; ++c) {
      d.requeue(*d.cameras[c], d.pending[c]);
      d.pending[c] = nullptr;
      lost += d.cameras[c]->lost;
    }
    d.lost.store(lost, std::memory_order_relaxed);
    ++d.delivered;
    return true;
  }
  return false;
}

}  // namespace voca::capture
