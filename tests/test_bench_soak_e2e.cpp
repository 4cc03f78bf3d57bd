// `voca bench soak` end to end through the binary, at CI's size: the live pipeline on the looping,
// lossy synthetic source holds its memory, allocates nothing per frame after the warm-up, accounts for
// every frame and writes poses; and bad options are refused with a message naming them.

#include <doctest/doctest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/test_support.h"

using nlohmann::json;
using voca::test::runVocaOutput;
using voca::test::ScratchDir;

TEST_CASE("voca bench soak: every frame accounted for, no allocation per frame, RSS flat, drops and damage seen") {
  const ScratchDir dir("soak");
  const std::filesystem::path report = dir / "soak.json";
  // 3000 frames at 8x real time (150 s of 20 Hz video): about a minute here, rendering included. Rates
  // high enough that drops and damage happen within the run for this seed.
  const voca::test::CommandOutput run = runVocaOutput(
      "bench soak --frames 3000 --warmup 1000 --speed 8 --drop-rate 0.01 --damage-rate 0.01 --seed 3 "
      "--json " +
      report.string());
  INFO(run.text);
  CHECK(run.exit_code == 0);
  std::ifstream in(report);
  REQUIRE(in.good());
  const json r = json::parse(in);
  CHECK(r["passed"].get<bool>());
  CHECK(r["failures"].empty());
  CHECK(r["frames_in"].get<std::int64_t>() == 3000);
  CHECK(r["unaccounted"].get<std::int64_t>() == 0);
  CHECK(r["frames_in"].get<std::int64_t>() ==
        r["written"].get<std::int64_t>() + r["dropped_at_source"].get<std::int64_t>() +
            r["skipped_to_keyframe"].get<std::int64_t>() + r["dropped_live"].get<std::int64_t>() +
            r["damaged"].get<std::int64_t>());
  CHECK(r["steady_allocations"].get<std::int64_t>() == 0);
  CHECK(r["steady_frames"].get<std::int64_t>() > 1500);
  CHECK(r["rss_growth_bytes"].get<std::int64_t>() < 1024 * 1024);
  CHECK(r["rss_at_warmup_bytes"].get<std::int64_t>() > 0);
  CHECK(r["dropped_at_source"].get<std::int64_t>() > 0);
  CHECK(r["damaged_packets"].get<std::int64_t>() > 0);
  CHECK(r["damaged"].get<std::int64_t>() > 0);  // the decoder saw the damage, not just the source
  CHECK(r["written"].get<std::int64_t>() > 1000);
  CHECK(r["passes"].get<std::int64_t>() > 1);  // the loop seam was crossed
  bool decode_stage = false;
  for (const json& stage : r["stages"]) decode_stage = decode_stage || stage["name"] == "decode";
  CHECK(decode_stage);
}

TEST_CASE("voca bench soak: bad options are refused with a message naming them") {
  const struct {
    const char* args;
    const char* message;
  } cases[] = {
      {"--frames 0", "--frames"},
      {"--frames 100 --warmup 100", "--warmup"},
      {"--drop-rate 1.5", "--drop-rate"},
      {"--damage-rate -0.1", "--damage-rate"},
      {"--speed 0", "--speed"},
      {"--frames abc", "--frames"},
      {"--input /nonexistent/soak-input", "/nonexistent/soak-input"},
  };
  for (const auto& c : cases) {
    const voca::test::CommandOutput run = runVocaOutput(std::string("bench soak ") + c.args);
    INFO(c.args << ": " << run.text);
    CHECK(run.exit_code != 0);
    CHECK(run.text.find(c.message) != std::string::npos);
  }
}
