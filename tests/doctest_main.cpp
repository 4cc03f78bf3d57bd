// The doctest main of every test executable: doctest's own run, then CTest's skip code when a
// test case could not run for want of ../shared/data (test_support.h), so such a run is reported
// as skipped rather than passed. Failures keep their non-zero code.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <cstdio>

#include "tests/test_support.h"

int main(int argc, char** argv) {
  doctest::Context context(argc, argv);
  const int status = context.run();
  if (context.shouldExit() || status != 0) return status;
  if (voca::test::sharedDataSkips() > 0) {
    std::printf("SKIPPED: %d check(s) need ../shared/data, which is not beside the checkout\n",
                voca::test::sharedDataSkips());
    return voca::test::kSkipReturnCode;
  }
  return 0;
}
