#pragma once
// Option checks for numbers. CLI11's PositiveNumber and NonNegativeNumber print their upper bound as
// a 309-digit number ("Value 0 not in range 0.000000 to 17976931348623157..."), and report text that
// is no number the same way; these say what was expected and what was given.

#include <CLI/CLI.hpp>

namespace voca::cli {

// "expected a number above 0, got 0" / "expected a number, got 'abc'".
CLI::Validator positiveNumber();
// "expected a number of 0 or more, got -1" / "expected a number, got 'abc'".
CLI::Validator nonNegativeNumber();

}  // namespace voca::cli
