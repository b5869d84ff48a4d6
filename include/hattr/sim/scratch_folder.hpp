#pragma once
/// Where throwaway studies are made (a power analysis's replicates, compare-strategies' studies):
/// a folder given by the caller, kept, or a new one in the system's temporary folder, removed with
/// this object (also when the work in it throws).

#include <filesystem>
#include <string_view>

namespace hattr::sim {

class ScratchFolder {
 public:
  /// `given` (created if missing), or a new folder TMP/hattr-`purpose`-XXXXXX when it is empty.
  /// Throws hattr::Error when the temporary one cannot be made.
  ScratchFolder(const std::filesystem::path& given, std::string_view purpose);
  ~ScratchFolder();
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;

  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }

 private:
  std::filesystem::path path_;
  bool own_ = false;  // made here: removed with this object
};

}  // namespace hattr::sim
