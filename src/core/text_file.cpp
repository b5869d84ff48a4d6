#include "hattr/core/text_file.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "hattr/core/error.hpp"

namespace hattr {

std::string readTextFile(const std::filesystem::path& file) {
  std::error_code ec;
  HATTR_THROW_UNLESS(!std::filesystem::is_directory(file, ec), "{}: expected a file, got a directory", file.string());
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot open for reading: {}", file.string(), std::strerror(errno)));
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

nlohmann::json parseJsonObject(std::string_view text, std::string_view source) {
  // The depth is checked as the parser descends, before anything deep is built.
  const auto bounded = [source](int depth, nlohmann::json::parse_event_t event, nlohmann::json&) {
    const bool opening = event == nlohmann::json::parse_event_t::object_start ||
                         event == nlohmann::json::parse_event_t::array_start;
    if (opening && depth >= kMaxJsonDepth) {
      throw InputError(fmt::format("{}: JSON nested deeper than {} levels: expected a configuration a few levels deep",
                                   source, kMaxJsonDepth));
    }
    return true;
  };
  nlohmann::json root;
  try {
    root = nlohmann::json::parse(text, bounded);
  } catch (const nlohmann::json::exception& e) {  // syntax, or a number beyond a double (1e400)
    throw InputError(fmt::format("{}: not valid JSON: {}", source, jsonLibraryMessage(e)));
  }
  HATTR_THROW_UNLESS(root.is_object(), "{}: expected a JSON object, got {}", source, root.type_name());
  return root;
}

std::string jsonLibraryMessage(const nlohmann::json::exception& e) {
  const std::string_view what = e.what();
  const auto end = what.starts_with("[json.exception.") ? what.find("] ") : std::string_view::npos;
  return std::string(end == std::string_view::npos ? what : what.substr(end + 2));
}

std::string jsonExcerpt(const nlohmann::json& value) { return textExcerpt(value.dump()); }

std::string textExcerpt(std::string_view text) {
  constexpr std::size_t kShown = 60;
  if (text.size() <= kShown) return std::string(text);
  return fmt::format("{}... ({} characters)", text.substr(0, kShown), text.size());
}

bool isSafeFileName(std::string_view name) noexcept {
  if (name.empty() || name.size() > 64 || name.front() == '.') return false;
  for (const char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
                    c == '-' || c == '.';
    if (!ok) return false;
  }
  return true;
}

bool staysInFolder(std::string_view name) noexcept {
  return !name.empty() && name.size() <= 255 && name != "." && name != ".." &&
         name.find_first_of(std::string_view("/\0", 2)) == std::string_view::npos;
}

bool isPlainRelativePath(const std::filesystem::path& path) noexcept {
  if (path.empty() || path.has_root_path()) return false;
  for (const auto& part : path) {
    if (part == ".." || part.empty()) return false;
  }
  return true;
}

}  // namespace hattr
