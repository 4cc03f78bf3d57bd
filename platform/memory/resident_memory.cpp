#include "platform/memory/resident_memory.h"

#include <fcntl.h>
#include <unistd.h>

#include <cstdlib>

namespace voca::platform {

ResidentMemory residentMemory() {
  // "size resident shared text lib data dt", in pages; a stack buffer, no stream.
  const int fd = ::open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return {};
  char text[128];
  const ssize_t n = ::read(fd, text, sizeof(text) - 1);
  ::close(fd);
  if (n <= 0) return {};
  text[n] = '\0';
  char* end = nullptr;
  std::strtoll(text, &end, 10);  // total program size
  const long long resident_pages = std::strtoll(end, &end, 10);
  const long long shared_pages = std::strtoll(end, &end, 10);
  const long page = ::sysconf(_SC_PAGESIZE);
  if (resident_pages <= 0 || shared_pages < 0 || page <= 0) return {};
  return {.bytes = static_cast<std::int64_t>(resident_pages) * page,
          .shared_bytes = static_cast<std::int64_t>(shared_pages) * page};
}

}  // namespace voca::platform
