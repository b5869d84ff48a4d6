#include "hattr/sim/scratch_folder.hpp"

#include <stdlib.h>

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr::sim {

ScratchFolder::ScratchFolder(const std::filesystem::path& given, std::string_view purpose) : own_(given.empty()) {
  if (!own_) {
    std::filesystem::create_directories(given);
    path_ = std::filesystem::absolute(given);
    return;
  }
  std::string pattern = (std::filesystem::temp_directory_path() / fmt::format("hattr-{}-XXXXXX", purpose)).string();
  HATTR_THROW_UNLESS(mkdtemp(pattern.data()) != nullptr, "{}: cannot make a scratch folder in {}", purpose,
                     std::filesystem::temp_directory_path().string());
  path_ = pattern;
}

ScratchFolder::~ScratchFolder() {
  std::error_code ignored;
  if (own_) std::filesystem::remove_all(path_, ignored);
}

}  // namespace hattr::sim
