#pragma once
/// Where the simulation's data files live (glyphs/, sim/): found at run time, never
/// compiled in as content.

#include <filesystem>

namespace hattr::sim {

/// The data directory: the environment variable HATTR_DATA_DIR if it is set and not empty, else
/// the share/hattr folder of the prefix this program is in (an installed prefix, or a build
/// folder, which stages the same layout: hattr/core/install_layout.hpp). Throws InputError if
/// HATTR_DATA_DIR names no directory, or if no prefix has one (saying where it looked).
/// Not for the servo thread.
std::filesystem::path defaultDataDir();

}  // namespace hattr::sim
