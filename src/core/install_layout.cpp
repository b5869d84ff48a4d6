#include "hattr/core/install_layout.hpp"

#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <sstream>

#ifndef HATTR_INSTALL_DATADIR
#define HATTR_INSTALL_DATADIR "share"
#endif
#ifndef HATTR_INSTALL_LIBDIR
#define HATTR_INSTALL_LIBDIR "lib"
#endif
#ifndef HATTR_INSTALL_PREFIX
#define HATTR_INSTALL_PREFIX "/usr/local"
#endif

namespace hattr {

namespace {

// The mapped file whose address range holds `address`, from the kernel's map of this process.
std::filesystem::path mappedFileHolding(std::uintptr_t address) {
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line)) {
    std::uintptr_t from = 0;
    std::uintptr_t to = 0;
    if (std::sscanf(line.c_str(), "%" SCNxPTR "-%" SCNxPTR, &from, &to) != 2) continue;
    if (address < from || address >= to) continue;
    const auto slash = line.find('/');
    if (slash == std::string::npos) return {};
    std::string file = line.substr(slash);
    if (file.ends_with(" (deleted)")) file.resize(file.size() - 10);
    return file;
  }
  return {};
}

}  // namespace

std::filesystem::path codeLocation() {
  const auto here = reinterpret_cast<std::uintptr_t>(&codeLocation);
  std::filesystem::path file = mappedFileHolding(here);
  std::error_code ec;
  if (file.empty()) file = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path{} : file;
}

std::filesystem::path relativeShareDir() { return std::filesystem::path(HATTR_INSTALL_DATADIR) / "hattr"; }

std::filesystem::path relativePluginDir() {
  return std::filesystem::path(HATTR_INSTALL_LIBDIR) / "hattr" / "plugins";
}

std::vector<std::filesystem::path> candidatePrefixes() {
  std::vector<std::filesystem::path> prefixes;
  const std::filesystem::path code = codeLocation();
  for (auto folder = code.parent_path(); !code.empty() && !folder.empty(); folder = folder.parent_path()) {
    prefixes.push_back(folder);
    if (folder == folder.root_path()) break;
  }
  // Last, the prefix this build was configured for: where a program of a C++ user that links
  // hattr's libraries, outside the prefix, finds an install made there.
  prefixes.emplace_back(HATTR_INSTALL_PREFIX);
  return prefixes;
}

std::optional<std::filesystem::path> findShareDir() {
  std::error_code ec;
  for (const auto& prefix : candidatePrefixes()) {
    const auto share = prefix / relativeShareDir();
    if (std::filesystem::is_directory(share / "glyphs", ec)) return share;
  }
  return std::nullopt;
}

std::optional<std::filesystem::path> findPluginDir() {
  std::error_code ec;
  for (const auto& prefix : candidatePrefixes()) {
    const auto plugins = prefix / relativePluginDir();
    if (std::filesystem::is_directory(plugins, ec)) return plugins;
  }
  return std::nullopt;
}

std::string searchedShareDirs() {
  std::ostringstream out;
  const auto prefixes = candidatePrefixes();
  for (std::size_t i = 0; i < prefixes.size(); ++i) out << (i == 0 ? "" : ", ") << (prefixes[i] / relativeShareDir()).string();
  return out.str();
}

}  // namespace hattr
