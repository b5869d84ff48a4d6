#pragma once
/// Reading configuration and data files whole: one place for the "cannot open" and "not valid
/// JSON" errors every loader gives. Not for the servo thread.

#include <cmath>
#include <filesystem>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "hattr/core/error.hpp"

namespace hattr {

/// The whole file as text. Throws InputError naming the file and the reason it cannot be read.
std::string readTextFile(const std::filesystem::path& file);

/// Values nested deeper than this are refused: no hattr file needs more than a few levels, and
/// the JSON library prints and copies values recursively.
inline constexpr int kMaxJsonDepth = 64;

/// Parses text that must hold a JSON object nested at most kMaxJsonDepth deep. Throws
/// InputError ("SOURCE: not valid JSON: ...", "SOURCE: expected a JSON object, got array",
/// "SOURCE: nested deeper than 64 levels ...").
nlohmann::json parseJsonObject(std::string_view text, std::string_view source_name);

/// The JSON library's message without its "[json.exception.type_error.302] " prefix.
std::string jsonLibraryMessage(const nlohmann::json::exception& e);

/// Runs `read`, which takes values out of parsed JSON: a JSON library error that slipped past
/// its checks (a value of an unexpected type) becomes an InputError naming `source`, never a
/// library exception.
template <class Read>
auto readingJson(std::string_view source, Read&& read) -> decltype(read()) {
  try {
    return read();
  } catch (const nlohmann::json::exception& e) {
    throw InputError(std::string(source) + ": " + jsonLibraryMessage(e));
  }
}

/// A number for JSON output: JSON has no NaN or infinity, so a value that is not finite is
/// written null (readers see "missing"); finite doubles round-trip exactly.
inline nlohmann::json jsonNumber(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

/// A value as it appears in a message: its JSON text, cut to about 60 characters ("[1, 2, ...]
/// (5000 characters)") so no message ever prints an unbounded value.
std::string jsonExcerpt(const nlohmann::json& value);
/// Any text as it appears in a message, cut the same way.
std::string textExcerpt(std::string_view text);

/// Whether `name` may become one component of a file path hattr writes (a subject id, a
/// skill): 1 to 64 letters, digits, '_', '-' or '.', not starting with '.' (so never "..",
/// never hidden, never a separator).
[[nodiscard]] bool isSafeFileName(std::string_view name) noexcept;
/// What isSafeFileName accepts, for messages.
inline constexpr std::string_view kSafeFileNameRule =
    "1 to 64 letters, digits, '_', '-' or '.', not starting with '.'";
/// Whether `name` can be one path component without leaving its folder: not empty, not "."
/// or "..", no '/', no NUL, at most 255 bytes. Looser than isSafeFileName: for names stored
/// before that rule (a subject "P 01"), which a writer must still place inside its folder.
[[nodiscard]] bool staysInFolder(std::string_view name) noexcept;
/// Whether `path` is relative and stays below its base: no root, no "..", not empty.
[[nodiscard]] bool isPlainRelativePath(const std::filesystem::path& path) noexcept;

}  // namespace hattr
