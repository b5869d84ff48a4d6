#pragma once
/// Writing a file whole or not at all: every file hattr writes (profiles, tables, reports,
/// power shards) goes through here. Not for the servo thread.

#include <filesystem>
#include <string_view>

namespace hattr {

/// What to do when the output file already exists.
enum class Overwrite { kRefuse, kReplace };

/// Writes `text` to `file` atomically (temporary file, fsync, rename): an existing file is
/// either kept (kRefuse: throws InputError "...: already exists; refusing to overwrite it") or
/// replaced whole, never left half-written. Throws hattr::Error when the file cannot be
/// written.
void writeFileAtomically(const std::filesystem::path& file, std::string_view text,
                         Overwrite overwrite = Overwrite::kRefuse);

}  // namespace hattr
