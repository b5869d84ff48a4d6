#include "hattr/sim/data_dir.hpp"

#include <cstdlib>
#include <string>

#include "hattr/core/error.hpp"
#include "hattr/core/install_layout.hpp"

namespace hattr::sim {

std::filesystem::path defaultDataDir() {
  if (const char* env = std::getenv("HATTR_DATA_DIR"); env != nullptr && *env != '\0') {
    const std::filesystem::path dir(env);
    HATTR_THROW_UNLESS(std::filesystem::is_directory(dir),
                       "HATTR_DATA_DIR: expected a directory holding glyphs/ and sim/, got \"{}\" (no such directory)",
                       dir.string());
    return dir;
  }
  if (auto share = findShareDir()) return *share;
  throw InputError(fmt::format(
      "data directory: HATTR_DATA_DIR is not set and no {} holding glyphs/ was found beside this program (looked in "
      "{}); reinstall hattr, or set HATTR_DATA_DIR to the folder holding glyphs/ and sim/",
      relativeShareDir().string(), searchedShareDirs()));
}

}  // namespace hattr::sim
