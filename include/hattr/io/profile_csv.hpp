#pragma once
/// The native haptic-profile file: CSV with a self-describing header. The format is
/// specified in docs/file-formats.md. Reading is strict: any problem throws
/// hattr::InputError naming the file, the line, the column, what was expected and what
/// was found. Not for the servo thread.

#include <filesystem>
#include <istream>
#include <ostream>
#include <string_view>

#include "hattr/core/atomic_file.hpp"
#include "hattr/core/haptic_profile.hpp"

namespace hattr::io {

/// The value of the `format` metadata line this version writes and reads.
inline constexpr std::string_view kProfileFormat = "hattr-profile/1";

/// Reads a profile file. Columns may be in millimetres or milliseconds (converted to SI).
HapticProfile readProfileCsv(const std::filesystem::path& file);
/// Reads a profile from a stream; `source_name` prefixes error messages.
HapticProfile readProfileCsv(std::istream& in, std::string_view source_name);

/// Writes a profile in SI units; floats are written so they read back bit for bit.
/// Throws InputError for an empty profile or metadata that cannot be written.
void writeProfileCsv(const HapticProfile& profile, std::ostream& out);
/// Writes atomically (temporary file, fsync, rename): an existing file is either kept
/// (kRefuse: throws InputError) or replaced whole, never left half-written.
void writeProfileCsv(const HapticProfile& profile, const std::filesystem::path& file,
                     Overwrite overwrite = Overwrite::kRefuse);

}  // namespace hattr::io
