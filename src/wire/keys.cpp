#include "hattr/wire/keys.hpp"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr::wire {
namespace {

static_assert(crypto_auth_KEYBYTES == kKeySize && crypto_kdf_KEYBYTES == kKeySize);
constexpr char kKdfContext[crypto_kdf_CONTEXTBYTES + 1] = "hattr-v2";
constexpr std::uint64_t kInitiatorToResponder = 1;
constexpr std::uint64_t kResponderToInitiator = 2;

bool isHex(char c) noexcept { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F'); }
std::uint8_t hexValue(char c) noexcept {
  return static_cast<std::uint8_t>(c <= '9' ? c - '0' : (c | 0x20) - 'a' + 10);
}

AuthKey derive(const AuthKey& shared, std::uint64_t subkey) {
  std::array<std::uint8_t, kKeySize> bytes{};
  if (crypto_kdf_derive_from_key(bytes.data(), bytes.size(), subkey, kKdfContext, shared.bytes().data()) != 0) {
    throw Error("libsodium could not derive a direction key (crypto_kdf_derive_from_key failed)");
  }
  AuthKey key(bytes);
  sodium_memzero(bytes.data(), bytes.size());
  return key;
}

/// A file descriptor closed on every way out.
struct FileDescriptor {
  int fd = -1;
  ~FileDescriptor() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

void initCrypto() {
  if (sodium_init() < 0) throw Error("libsodium could not be initialised (sodium_init failed)");
}

AuthKey::~AuthKey() { sodium_memzero(bytes_.data(), bytes_.size()); }

DirectionKeys directionKeys(const AuthKey& shared, Role role) {
  initCrypto();
  AuthKey to_responder = derive(shared, kInitiatorToResponder);
  AuthKey to_initiator = derive(shared, kResponderToInitiator);
  return role == Role::kInitiator ? DirectionKeys{to_responder, to_initiator} : DirectionKeys{to_initiator, to_responder};
}

// A regular file only its owner may open; exactly 64 hex characters and an optional
// newline. The messages never show key material.
AuthKey readKeyFile(const std::filesystem::path& file) {
  const FileDescriptor in{::open(file.c_str(), O_RDONLY | O_CLOEXEC)};
  HATTR_THROW_UNLESS(in.fd >= 0, "key file {}: cannot open it for reading: {}", file.string(), std::strerror(errno));
  struct stat info {};
  HATTR_THROW_UNLESS(::fstat(in.fd, &info) == 0 && S_ISREG(info.st_mode),
                     "key file {}: expected a regular file, got something else", file.string());
  HATTR_THROW_UNLESS((info.st_mode & 077) == 0,
                     "key file {}: expected a file only its owner can read (mode 0600, as for an ssh private key), "
                     "got mode {:04o}, open to group or others; run `chmod 600 {}` (and make a new key if others "
                     "may have read it)",
                     file.string(), info.st_mode & 07777, file.string());
  char buffer[130];
  std::size_t size = 0;
  for (ssize_t n = 1; n > 0 && size < sizeof buffer; size += static_cast<std::size_t>(n)) {
    n = ::read(in.fd, buffer + size, sizeof buffer - size);
    HATTR_THROW_UNLESS(n >= 0, "key file {}: cannot read it: {}", file.string(), std::strerror(errno));
    if (n == 0) break;
  }
  const std::string_view expected = "expected 64 hexadecimal characters (a 32-byte key) and at most a newline";
  std::string_view body(buffer, size);
  if (body.ends_with('\n')) body.remove_suffix(1);
  std::array<std::uint8_t, kKeySize> bytes{};
  const auto wipe = [&] {
    sodium_memzero(bytes.data(), bytes.size());
    sodium_memzero(buffer, sizeof buffer);
  };
  if (size >= sizeof buffer || body.size() != 2 * kKeySize) {
    wipe();
    if (size >= sizeof buffer) throw InputError(fmt::format("key file {}: {}, got a longer file", file.string(), expected));
    throw InputError(fmt::format("key file {}: {}, got {} characters before the end or newline", file.string(),
                                 expected, body.size()));
  }
  for (std::size_t i = 0; i < body.size(); ++i) {
    if (!isHex(body[i])) {
      wipe();
      throw InputError(fmt::format("key file {}: {}, got a character that is not hexadecimal at position {}",
                                   file.string(), expected, i + 1));
    }
    bytes[i / 2] = static_cast<std::uint8_t>(bytes[i / 2] << 4 | hexValue(body[i]));
  }
  AuthKey key(bytes);
  wipe();
  return key;
}

AuthKey randomKey() {
  initCrypto();
  std::array<std::uint8_t, kKeySize> bytes{};
  crypto_auth_keygen(bytes.data());
  AuthKey key(bytes);
  sodium_memzero(bytes.data(), bytes.size());
  return key;
}

// O_EXCL unless overwriting, never through a symbolic link; mode 0600 from creation on, and
// forced on a replaced file.
void writeKeyFile(const std::filesystem::path& file, const AuthKey& key, bool overwrite) {
  const int flags = O_WRONLY | O_CREAT | O_CLOEXEC | O_NOFOLLOW | (overwrite ? O_TRUNC : O_EXCL);
  const FileDescriptor out{::open(file.c_str(), flags, 0600)};
  if (out.fd < 0 && errno == EEXIST) {
    throw InputError(fmt::format("key file {}: exists already; expected a new file name, or --force to replace it",
                                 file.string()));
  }
  if (out.fd < 0 && errno == ELOOP) {
    throw InputError(fmt::format("key file {}: is a symbolic link; expected a plain file name (a key is never "
                                 "written through a link)",
                                 file.string()));
  }
  if (out.fd < 0) throw InputError(fmt::format("key file {}: cannot create it: {}", file.string(), std::strerror(errno)));
  char hex[2 * kKeySize + 1];
  sodium_bin2hex(hex, sizeof hex, key.bytes().data(), kKeySize);
  hex[2 * kKeySize] = '\n';
  const bool ok = ::fchmod(out.fd, 0600) == 0 &&
                  ::write(out.fd, hex, sizeof hex) == static_cast<ssize_t>(sizeof hex) && ::fsync(out.fd) == 0;
  const int error = errno;
  sodium_memzero(hex, sizeof hex);
  if (!ok) throw Error(fmt::format("key file {}: cannot write it: {}", file.string(), std::strerror(error)));
}

}  // namespace hattr::wire
