// Fuzzes the study-file reader: any input either becomes a study definition that writes back
// to JSON and reads again to the same protocol, or is refused with hattr::InputError. Nothing
// else: no crash, no other exception, no unbounded recursion.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "hattr/core/error.hpp"
#include "hattr/session/study.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  hattr::session::StudyDefinition study;
  try {
    study = hattr::session::parseStudy(text, "fuzz.json", "", false);
  } catch (const hattr::InputError&) {
    return 0;
  }
  const hattr::session::StudyDefinition again =
      hattr::session::parseStudy(hattr::session::studyToJson(study).dump(), "fuzz-again.json", "", false);
  if (again.name != study.name || again.modes != study.modes || again.subjects.size() != study.subjects.size() ||
      again.protocol.training_trials != study.protocol.training_trials ||
      again.protocol.recall_trials != study.protocol.recall_trials) {
    __builtin_trap();
  }
  return 0;
}
