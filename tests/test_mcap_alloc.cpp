// McapWriter::write makes no heap allocation: the record's fixed fields are built in the writer and the
// payload goes to the OS as it is, whatever its size. This executable replaces the global operator
// new/delete with counting versions.

#include <doctest/doctest.h>

#include <cstdint>
#include <vector>

#include "drivers/mcap/mcap_writer.h"
#include "tests/test_alloc_counter.h"
#include "tests/test_support.h"

TEST_CASE("mcap writer: no heap allocation per message") {
  voca::test::ScratchDir dir("mcap-alloc");
  voca::mcap::McapWriter writer(dir / "alloc.mcap", "alloc");
  const auto schema = writer.addSchema("s", "jsonschema", std::string_view("{}"));
  const auto pose = writer.addChannel(schema, "/pose", "json");
  const auto image = writer.addChannel(0, "/image", "x-jpeg");
  // Payloads of every size from empty to 200 kB, prepared before the count.
  std::vector<std::vector<std::uint8_t>> payloads;
  for (std::size_t size : {0, 1, 64, 1000, 65536, 200000}) payloads.emplace_back(size, std::uint8_t{0x5a});

  const long before = voca::test::g_allocations.load();
  std::uint32_t sequence = 0;
  for (int round = 0; round < 200; ++round) {
    for (const auto& payload : payloads) {
      const std::uint64_t t_ns = 1'000'000ull * sequence;
      REQUIRE(writer.write(round % 2 == 0 ? pose : image, sequence++, t_ns, t_ns, payload));
    }
  }
  const long allocations = voca::test::g_allocations.load() - before;
  CHECK(allocations == 0);
  CHECK(writer.messageCount() == 1200);
  CHECK(writer.close());
}
