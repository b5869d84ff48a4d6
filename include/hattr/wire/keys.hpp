#pragma once
/// Keys of the wire protocol (docs/protocol.md, "Keys"): the 32-byte shared key both sides
/// hold in a key file, and the two direction keys derived from it (libsodium's KDF), one
/// per direction, so a packet sent one way never verifies the other way.
///
/// Threads: key files are setup code and throw hattr::InputError / hattr::Error; AuthKey
/// itself is plain data.

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>

namespace hattr::wire {

inline constexpr std::size_t kKeySize = 32;  ///< crypto_auth key

/// A 32-byte authentication key. Never printed; wiped on destruction.
class AuthKey {
 public:
  AuthKey() = default;
  explicit AuthKey(const std::array<std::uint8_t, kKeySize>& bytes) noexcept : bytes_(bytes) {}
  AuthKey(const AuthKey&) = default;
  AuthKey& operator=(const AuthKey&) = default;
  ~AuthKey();
  [[nodiscard]] const std::array<std::uint8_t, kKeySize>& bytes() const noexcept { return bytes_; }

 private:
  std::array<std::uint8_t, kKeySize> bytes_{};
};

/// Which end of a session a side is: the initiator says HELLO (the udp:// client, the
/// mentoring follower), the responder answers (the device server, the mentoring leader).
enum class Role { kInitiator, kResponder };

/// The keys one side uses: it signs with `send` and verifies with `receive`.
struct DirectionKeys {
  AuthKey send;
  AuthKey receive;
};

/// The direction keys of `role` derived from the shared key: crypto_kdf_derive_from_key with
/// context "hattr-v2", subkey 1 for initiator → responder and 2 for responder → initiator.
[[nodiscard]] DirectionKeys directionKeys(const AuthKey& shared, Role role);

/// Reads a key file: exactly 64 hexadecimal characters, optionally followed by one newline,
/// in a regular file that neither group nor others may read (mode 0600 or 0400, as ssh asks
/// of private keys). Throws InputError naming the file and what was expected and found (never
/// key material).
[[nodiscard]] AuthKey readKeyFile(const std::filesystem::path& file);
/// A fresh random key (libsodium randombytes).
[[nodiscard]] AuthKey randomKey();
/// Writes `key` as 64 hex characters and a newline, file mode 0600, never through a symbolic
/// link. Refuses to replace an existing file unless `overwrite` (InputError); other I/O
/// failures throw hattr::Error.
void writeKeyFile(const std::filesystem::path& file, const AuthKey& key, bool overwrite);

/// Makes sure libsodium is initialised (idempotent, thread-safe). Throws hattr::Error if not.
void initCrypto();

}  // namespace hattr::wire
