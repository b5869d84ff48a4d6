#pragma once
/// Where hattr finds what it reads at run time: the glyphs, the simulation data, the open pen's
/// firmware (PREFIX/share/hattr) and the driver plugins (PREFIX/LIBDIR/hattr/plugins). The prefix
/// is found from where this code is (the executable, or the shared object it is linked into, as
/// the Python module), never from a path compiled in from the source tree: an installed hattr and
/// a build folder (which stages the same layout) are both prefixes. Not for the servo thread.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace hattr {

/// The file that holds this code: the executable, or the shared object (Python module, plugin)
/// hattr's libraries are linked into, as the kernel maps it (an absolute path). Empty if it cannot
/// be told (no /proc).
std::filesystem::path codeLocation();

/// The share folder's path relative to a prefix ("share/hattr") and the plugin folder's
/// ("lib/x86_64-linux-gnu/hattr/plugins" on Debian), as the build's install directories set them.
std::filesystem::path relativeShareDir();
std::filesystem::path relativePluginDir();

/// The folders a prefix would be: each ancestor of codeLocation()'s folder, nearest first, then
/// the prefix this build was configured to install into (CMAKE_INSTALL_PREFIX), for programs of
/// C++ users that link hattr's libraries from outside the prefix.
std::vector<std::filesystem::path> candidatePrefixes();

/// The nearest candidate prefix P with P/relativeShareDir() a directory holding glyphs/; nullopt
/// if there is none.
std::optional<std::filesystem::path> findShareDir();

/// The nearest candidate prefix P with P/relativePluginDir() a directory; nullopt if none.
std::optional<std::filesystem::path> findPluginDir();

/// The places findShareDir() looked, for an error message ("/opt/hattr/share/hattr, /opt/share/hattr, ...").
std::string searchedShareDirs();

}  // namespace hattr
