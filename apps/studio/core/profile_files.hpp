#pragma once
/// Loading and saving haptic profiles from the studio: io::readProfileCsv and the atomic
/// io::writeProfileCsv, with the studio's rules — an existing file is never replaced without
/// the person's confirmation, and a failed save keeps the take in memory. Not for the servo
/// thread.

#include <filesystem>
#include <string>

#include "hattr/core/haptic_profile.hpp"

namespace hattr::studio {

enum class SaveOutcome {
  kSaved,              ///< written (atomically)
  kNeedsConfirmation,  ///< the file exists and replacing it was not confirmed; nothing written
};

/// Writes `profile` to `file` atomically. An existing file is replaced only when
/// `replace_confirmed`. Throws hattr::InputError naming the file when writing fails.
SaveOutcome saveProfile(const HapticProfile& profile, const std::filesystem::path& file, bool replace_confirmed);

/// An expert take named for saving: `subject` = the expert's name, `skill` = the character.
/// Leading and trailing blanks are dropped. Throws InputError (saying which field and what
/// was found) for an empty name or character, or one holding a line break or another
/// control character (a metadata line of the file cannot hold it).
HapticProfile nameTake(HapticProfile take, const std::string& expert_name, const std::string& character);

/// A file name for a take: "expert_<name>_<character>.csv", characters that are awkward in
/// file names replaced by '_'.
std::string suggestedTakeFileName(const std::string& expert_name, const std::string& character);

/// Checks `profile` can be a training reference: at least two samples, some pen-down. Throws
/// InputError starting with `name`, saying what was expected and what was found.
void checkReferenceProfile(const HapticProfile& profile, const std::string& name);

/// Reads a reference profile for training and checks it can be one (checkReferenceProfile,
/// named by the file): a profile CSV file, or a person's template in a profile library,
/// library:PATH#PERSON/SKILL (built from their genuine recordings, library::libraryTemplate).
HapticProfile loadReferenceProfile(const std::string& file);

}  // namespace hattr::studio
