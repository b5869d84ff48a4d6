#pragma once
/// Where the simulation's data files live (glyphs/, sim/): found at run time, never
/// compiled in as content.

#include <filesystem>

namespace hattr::sim {

/// The data directory: the environment variable HATTR_DATA_DIR if it is set and not empty,
/// else the source tree's data/ folder as the build defines it (HATTR_SOURCE_DATA_DIR).
/// Throws InputError if HATTR_DATA_DIR names no directory, or if neither is available.
/// Not for the servo thread.
std::filesystem::path defaultDataDir();

}  // namespace hattr::sim
