#include "hattr/sim/data_dir.hpp"

#include <cstdlib>
#include <string>

#include "hattr/core/error.hpp"

namespace hattr::sim {

std::filesystem::path defaultDataDir() {
  if (const char* env = std::getenv("HATTR_DATA_DIR"); env != nullptr && *env != '\0') {
    const std::filesystem::path dir(env);
    HATTR_THROW_UNLESS(std::filesystem::is_directory(dir),
                       "HATTR_DATA_DIR: expected a directory holding glyphs/ and sim/, got \"{}\" (no such directory)",
                       dir.string());
    return dir;
  }
#ifdef HATTR_SOURCE_DATA_DIR
  const std::filesystem::path built_in(HATTR_SOURCE_DATA_DIR);
  HATTR_THROW_UNLESS(std::filesystem::is_directory(built_in),
                     "data directory: HATTR_DATA_DIR is not set and the source tree's data folder \"{}\" does not "
                     "exist; set HATTR_DATA_DIR to the folder holding glyphs/ and sim/",
                     built_in.string());
  return built_in;
#else
  throw InputError(
      "data directory: HATTR_DATA_DIR is not set and this build has no source data folder; set HATTR_DATA_DIR to "
      "the folder holding glyphs/ and sim/");
#endif
}

}  // namespace hattr::sim
