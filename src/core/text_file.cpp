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
  nlohmann::json root;
  try {
    root = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(fmt::format("{}: not valid JSON: {}", source, e.what()));
  }
  HATTR_THROW_UNLESS(root.is_object(), "{}: expected a JSON object, got {}", source, root.type_name());
  return root;
}

}  // namespace hattr
