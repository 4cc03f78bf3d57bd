#include "drivers/network/stream_url.h"

#include <algorithm>

#include <fmt/core.h>

#include "voca/core/error.h"

namespace voca::network {

void requireStreamPort(const std::string& url) {
  const std::size_t scheme_end = url.find("://");
  if (scheme_end == std::string::npos) return;
  const std::string scheme = url.substr(0, scheme_end);
  if (scheme != "udp" && scheme != "tcp" && scheme != "rtp") return;
  const std::size_t host_start = scheme_end + 3;
  const std::size_t host_end = std::min(url.find_first_of("/?", host_start), url.size());
  const std::string authority = url.substr(host_start, host_end - host_start);
  // An IPv6 host is bracketed ([::1]:5000): the port follows the closing bracket.
  const std::size_t bracket = authority.rfind(']');
  const std::size_t colon = authority.rfind(':');
  const bool has_port = colon != std::string::npos && (bracket == std::string::npos || colon > bracket);
  const std::string port = has_port ? authority.substr(colon + 1) : std::string();
  const bool digits = !port.empty() && port.size() <= 5 &&
                      std::all_of(port.begin(), port.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (!has_port || port.empty()) {
    throw InputError(fmt::format("{}: no port; give one, as in {}://127.0.0.1:5000", url, scheme));
  }
  if (!digits || std::stoi(port) < 1 || std::stoi(port) > 65535) {
    throw InputError(fmt::format("{}: port {} is not a number from 1 to 65535", url, port));
  }
}

}  // namespace voca::network
