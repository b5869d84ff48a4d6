#include "core/profile_files.hpp"

#include <algorithm>
#include <cctype>

#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/library/profile_template.hpp"

namespace hattr::studio {
namespace {

std::string trimmed(const std::string& text) {
  const auto blank = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  const auto first = std::find_if_not(text.begin(), text.end(), blank);
  const auto last = std::find_if_not(text.rbegin(), text.rend(), blank).base();
  return first < last ? std::string(first, last) : std::string();
}

bool hasControlCharacter(const std::string& text) {
  return std::any_of(text.begin(), text.end(), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return u < 0x20 || u == 0x7f;
  });
}

void checkField(const std::string& value, const char* field, const std::string& original) {
  HATTR_THROW_UNLESS(!value.empty(), "{}: expected a non-empty text, got \"{}\"", field, original);
  HATTR_THROW_UNLESS(!hasControlCharacter(value),
                     "{}: expected one line of text without control characters, got \"{}\"", field, original);
}

}  // namespace

SaveOutcome saveProfile(const HapticProfile& profile, const std::filesystem::path& file, bool replace_confirmed) {
  std::error_code ec;
  if (!replace_confirmed && std::filesystem::exists(file, ec)) return SaveOutcome::kNeedsConfirmation;
  // kRefuse still guards the race where the file appears after the check.
  io::writeProfileCsv(profile, file, replace_confirmed ? hattr::Overwrite::kReplace : hattr::Overwrite::kRefuse);
  return SaveOutcome::kSaved;
}

HapticProfile nameTake(HapticProfile take, const std::string& expert_name, const std::string& character) {
  const std::string name = trimmed(expert_name);
  const std::string skill = trimmed(character);
  checkField(name, "expert name", expert_name);
  checkField(skill, "character", character);
  take.metadata().subject = name;
  take.metadata().skill = skill;
  return take;
}

std::string suggestedTakeFileName(const std::string& expert_name, const std::string& character) {
  std::string out = "expert_" + trimmed(expert_name) + "_" + trimmed(character);
  // Keep letters (any script: bytes >= 0x80 pass), digits, '-', '_' and '.'.
  std::replace_if(
      out.begin(), out.end(),
      [](char c) {
        const auto u = static_cast<unsigned char>(c);
        return !(u >= 0x80 || std::isalnum(u) || c == '-' || c == '_' || c == '.');
      },
      '_');
  return out + ".csv";
}

void checkReferenceProfile(const HapticProfile& profile, const std::string& name) {
  HATTR_THROW_UNLESS(profile.size() >= 2, "{}: a reference needs at least 2 samples, got {}", name, profile.size());
  HATTR_THROW_UNLESS(profile.penDownCount() > 0,
                     "{}: a reference needs samples with the pen down (something written), got none of {}", name,
                     profile.size());
}

HapticProfile loadReferenceProfile(const std::string& file) {
  HapticProfile profile = library::readReference(file);
  checkReferenceProfile(profile, file);
  return profile;
}

}  // namespace hattr::studio
