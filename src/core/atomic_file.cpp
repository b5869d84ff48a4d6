#include "hattr/core/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr {

void writeFileAtomically(const std::filesystem::path& file, std::string_view text, Overwrite overwrite) {
  std::error_code ec;
  HATTR_THROW_UNLESS(overwrite == Overwrite::kReplace || !std::filesystem::exists(file, ec),
                     "{}: already exists; refusing to overwrite it", file.string());
  const std::filesystem::path tmp = file.string() + fmt::format(".tmp-{}", ::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    throw Error(fmt::format("{}: cannot create: {}", tmp.string(), std::strerror(errno)));
  }
  std::size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      ::close(fd);
      std::filesystem::remove(tmp, ec);
      throw Error(fmt::format("{}: write failed: {}", tmp.string(), std::strerror(err)));
    }
    written += static_cast<std::size_t>(n);
  }
  const bool synced = ::fsync(fd) == 0;
  const int sync_errno = errno;
  ::close(fd);
  if (!synced) {
    std::filesystem::remove(tmp, ec);
    throw Error(fmt::format("{}: fsync failed: {}", tmp.string(), std::strerror(sync_errno)));
  }
  // Publish: link() fails if the file appeared meanwhile; rename() replaces it whole.
  if (overwrite == Overwrite::kRefuse) {
    const int linked = ::link(tmp.c_str(), file.c_str());
    const int link_errno = errno;
    std::filesystem::remove(tmp, ec);
    HATTR_THROW_UNLESS(linked == 0 || link_errno != EEXIST, "{}: already exists; refusing to overwrite it",
                       file.string());
    if (linked != 0) {
      throw Error(fmt::format("{}: cannot create: {}", file.string(), std::strerror(link_errno)));
    }
    return;
  }
  std::filesystem::rename(tmp, file);
}

}  // namespace hattr
