#pragma once
/// Reading configuration and data files whole: one place for the "cannot open" and "not valid
/// JSON" errors every loader gives. Not for the servo thread.

#include <filesystem>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace hattr {

/// The whole file as text. Throws InputError naming the file and the reason it cannot be read.
std::string readTextFile(const std::filesystem::path& file);

/// Parses text that must hold a JSON object. Throws InputError ("SOURCE: not valid JSON: ...",
/// "SOURCE: expected a JSON object, got array").
nlohmann::json parseJsonObject(std::string_view text, std::string_view source_name);

}  // namespace hattr
