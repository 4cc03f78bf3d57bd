#include "tools/voca/number_checks.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <string>

namespace voca::cli {

namespace {

// Whether the whole text is one finite number (then in `value`).
bool parseFinite(const std::string& text, double& value) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && errno == 0 && std::isfinite(value);
}

CLI::Validator numberAtLeast(bool strictly, const char* description) {
  return CLI::Validator(
      [strictly](std::string& text) -> std::string {
        double value = 0.0;
        if (!parseFinite(text, value)) return "expected a number, got '" + text + "'";
        if (strictly ? value > 0.0 : value >= 0.0) return {};
        return std::string(strictly ? "expected a number above 0" : "expected a number of 0 or more") + ", got " + text;
      },
      description);
}

}  // namespace

CLI::Validator positiveNumber() { return numberAtLeast(true, "POSITIVE"); }
CLI::Validator nonNegativeNumber() { return numberAtLeast(false, "NONNEGATIVE"); }

}  // namespace voca::cli
