#pragma once
// The port of a stream URL (udp://host:port, tcp://host:port?listen=1, rtp://...), checked before
// libavformat sees it: it wraps a port above 65535 (99999 sent to 34463) and waits for a URL
// without one until its timeout.

#include <string>

namespace voca::network {

// Throws InputError naming the URL when a udp, tcp or rtp URL has no port or one outside 1..65535.
// Other URLs (files, other schemes) pass unchecked.
void requireStreamPort(const std::string& url);

}  // namespace voca::network
