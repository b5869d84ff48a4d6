// Fuzzes the haptic-profile CSV reader: any input either parses into a valid profile
// that writes and reads back identically, or throws hattr::InputError. Nothing else.

#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  hattr::HapticProfile profile;
  try {
    profile = hattr::io::readProfileCsv(in, "fuzz.csv");
  } catch (const hattr::InputError&) {
    return 0;
  }
  std::stringstream text;
  hattr::io::writeProfileCsv(profile, text);
  const hattr::HapticProfile again = hattr::io::readProfileCsv(text, "fuzz-again.csv");
  // Metadata values are trimmed on read, so compare the samples, which must be exact.
  if (!(again.samples() == profile.samples())) __builtin_trap();
  return 0;
}
