// The live view through the runner's own options (VoRunOptions::view.address, as the library API
// will use it), on a rendered raw sequence: an address in use stops the run before anything is
// written; with the view on, the trajectory is the one without it; and the stages fill what sinks
// ask for (FrameSinkNeeds) and nothing when no sink asks.

#include <arpa/inet.h>
#include <doctest/doctest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fstream>
#include <iterator>

#include "pipeline/vo/vo_runner.h"
#include "test_support.h"

namespace fs = std::filesystem;
using namespace voca;

namespace {

// A rendered 1 s raw sequence (no encoding: the view must work without motion vectors), made once.
struct Rendered {
  test::ScratchDir dir{"view-run"};
  fs::path raw = dir / "synth";
  Rendered() {
    REQUIRE(test::renderSynth(raw, "--motion fast-rotation --seconds 1 --supersample 1") == 0);
  }
};

const Rendered& rendered() {
  static const Rendered sequence;
  return sequence;
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Records what reached the sinks, and asks for what it is told to.
class RecordingSink final : public pipeline::FrameSink {
 public:
  explicit RecordingSink(pipeline::FrameSinkNeeds needs) : needs_(needs) {}
  void consume(const pipeline::FrameSlot& slot) override {
    ++frames;
    max_landmarks = std::max(max_landmarks, slot.landmarks_world.size());
    max_traces = std::max(max_traces, slot.left_traces.size());
  }
  pipeline::FrameSinkNeeds needs() const override { return needs_; }
  int frames = 0;
  std::size_t max_landmarks = 0, max_traces = 0;

 private:
  pipeline::FrameSinkNeeds needs_;
};

pipeline::VoRunOptions quietRun(const fs::path& trajectory) {
  pipeline::VoRunOptions options;
  options.input = rendered().raw;
  options.trajectory_file = trajectory;
  options.progress = false;
  return options;
}

}  // namespace

TEST_CASE("a view address in use stops the run before anything is written") {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  REQUIRE(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
  REQUIRE(::listen(fd, 1) == 0);
  socklen_t size = sizeof addr;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &size);
  const std::string address = "127.0.0.1:" + std::to_string(ntohs(addr.sin_port));

  const fs::path trajectory = rendered().dir / "in_use.txt";
  pipeline::VoRunOptions options = quietRun(trajectory);
  options.view.address = address;
  const std::string error = test::inputErrorOf([&] { pipeline::runVisualOdometry(options); });
  ::close(fd);
  CHECK(error.find("cannot serve the view on " + address + ": Address already in use") != std::string::npos);
  CHECK_FALSE(fs::exists(trajectory));
}

TEST_CASE("with the view on the trajectory is unchanged, and the stages fill only what sinks ask for") {
  const fs::path plain_file = rendered().dir / "plain.txt";
  RecordingSink plain_sink({});
  pipeline::VoRunOptions plain = quietRun(plain_file);
  plain.extra_sinks = {&plain_sink};
  const pipeline::VoRunResult plain_result = pipeline::runVisualOdometry(plain);
  REQUIRE(plain_result.frames == 20);
  CHECK(plain_sink.frames == 20);
  CHECK(plain_sink.max_landmarks == 0);  // nobody asked: the backend copied none
  CHECK(plain_sink.max_traces == 0);

  // A sink of its own asking for landmarks (an MCAP recorder, say) gets them without a view.
  RecordingSink asking({.left_traces = false, .landmarks = true});
  pipeline::VoRunOptions with_sink = quietRun(rendered().dir / "asking.txt");
  with_sink.extra_sinks = {&asking};
  pipeline::runVisualOdometry(with_sink);
  CHECK(asking.max_landmarks > 20);
  CHECK(asking.max_traces == 0);

  const fs::path view_file = rendered().dir / "view.txt";
  RecordingSink beside_view({});
  pipeline::VoRunOptions with_view = quietRun(view_file);
  with_view.view.address = "127.0.0.1:0";
  with_view.extra_sinks = {&beside_view};
  const pipeline::VoRunResult view_result = pipeline::runVisualOdometry(with_view);
  CHECK(view_result.frames == 20);
  CHECK(beside_view.max_landmarks > 20);  // the view asks for landmarks and traces
  CHECK(beside_view.max_traces > 20);
  CHECK(readFile(view_file) == readFile(plain_file));
  CHECK(readFile(rendered().dir / "asking.txt") == readFile(plain_file));
}
