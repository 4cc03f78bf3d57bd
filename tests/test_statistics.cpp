// The statistics sink's guess-distance histogram (the paper's Fig. 5): quantiles on known samples,
// and samples beyond its range reported as beyond, not as the last bin's value.

#include <doctest/doctest.h>

#include <cmath>

#include "pipeline/sinks/statistics_sink.h"

using voca::pipeline::DistanceHistogram;

TEST_CASE("statistics: distance quantiles are bin midpoints; beyond the range they say so") {
  DistanceHistogram h;
  CHECK(h.quantile(0.5) == 0.0);
  for (int i = 0; i < 100; ++i) h.record(0.5 + 0.1 * i);  // 0.5 .. 10.4 px
  CHECK(h.count() == 100);
  CHECK(h.quantile(0.0) == doctest::Approx(0.505));
  CHECK(h.quantile(0.5) == doctest::Approx(5.505));  // rank 50: 5.5 px
  CHECK(h.quantile(1.0) == doctest::Approx(10.405));
  CHECK(h.formatQuantile(0.5) == "5.505");

  // Fast motion puts the previous position 20-60 px away: such samples must not read as 16 px.
  DistanceHistogram far;
  for (int i = 0; i < 10; ++i) far.record(1.0);
  for (int i = 0; i < 30; ++i) far.record(20.0 + i);
  CHECK(far.quantile(0.1) == doctest::Approx(1.005));
  CHECK(std::isinf(far.quantile(0.5)));
  CHECK(far.formatQuantile(0.5) == "> 16");
  CHECK(far.bins().back() == 30);
}
