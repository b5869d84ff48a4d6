// Labelled profiles from an SVC2004 folder and from a study's completed trials.

#include "hattr/library/sources.hpp"

#include <algorithm>
#include <optional>
#include <string_view>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/guidance/training_guidance.hpp"

namespace hattr::library {

namespace {

// The two numbers of a file name U<writer>S<signature>.TXT, as written.
struct Svc2004FileName {
  std::string_view writer_digits;
  std::string_view signature_digits;
};

// The run of digits at the start of text.
std::string_view leadingDigits(std::string_view text) {
  std::size_t n = 0;
  while (n < text.size() && text[n] >= '0' && text[n] <= '9') ++n;
  return text.substr(0, n);
}

// The name's numbers, or nothing when the name is not U<digits>S<digits>.TXT.
std::optional<Svc2004FileName> svc2004FileName(std::string_view name) {
  constexpr std::string_view kSuffix = ".TXT";
  if (name.size() < 1 + kSuffix.size() || name.front() != 'U' || !name.ends_with(kSuffix)) return std::nullopt;
  name = name.substr(1, name.size() - 1 - kSuffix.size());
  const std::string_view writer = leadingDigits(name);
  if (writer.empty() || writer.size() >= name.size() || name[writer.size()] != 'S') return std::nullopt;
  const std::string_view signature = name.substr(writer.size() + 1);
  if (signature.empty() || leadingDigits(signature).size() != signature.size()) return std::nullopt;
  return Svc2004FileName{writer, signature};
}

}  // namespace

LabelledProfiles readSvc2004Folder(const std::filesystem::path& folder, const io::TabletCalibration& calibration) {
  HATTR_THROW_UNLESS(std::filesystem::is_directory(folder),
                     "{}: not a folder; expected the SVC2004 Task 2 folder of U<writer>S<signature>.TXT files",
                     folder.string());
  // The files in writer, then signature order.
  std::vector<std::tuple<int, int, std::filesystem::path>> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (!entry.is_regular_file()) continue;
    const std::string file_name = entry.path().filename().string();
    const auto name = svc2004FileName(file_name);
    if (!name) continue;
    HATTR_THROW_UNLESS(name->writer_digits.size() <= 6 && name->signature_digits.size() <= 6,
                       "{}: numbers {} and {} in the name; expected at most 6 digits each", entry.path().string(),
                       name->writer_digits, name->signature_digits);
    const int writer = std::stoi(std::string(name->writer_digits));
    const int signature = std::stoi(std::string(name->signature_digits));
    HATTR_THROW_UNLESS(writer >= 1 && signature >= 1 && signature <= 40,
                       "{}: signature {} of writer {}; expected writers from 1 and signatures 1-40 (1-20 genuine, "
                       "21-40 skilled forgeries)",
                       entry.path().string(), signature, writer);
    files.emplace_back(writer, signature, entry.path());
  }
  HATTR_THROW_UNLESS(!files.empty(),
                     "{}: no U<writer>S<signature>.TXT file; expected the SVC2004 Task 2 folder (e.g. U1S1.TXT)",
                     folder.string());
  std::sort(files.begin(), files.end());

  LabelledProfiles out;
  out.reserve(files.size());
  for (const auto& [writer, signature, file] : files) {
    HapticProfile profile = io::importSvc2004(file, calibration);
    EntryLabels l;
    l.person = fmt::format("U{}", writer);
    l.key = fmt::format("svc2004/U{}S{}", writer, signature);
    l.skill = "signature";
    l.session = signature <= 10 ? "1" : (signature <= 20 ? "2" : "");
    l.authenticity = signature <= 20 ? Authenticity::kGenuine : Authenticity::kImitation;
    l.device = profile.metadata().device;
    l.source = profile.metadata().source;
    profile.metadata().subject = l.person;
    profile.metadata().skill = l.skill;
    out.emplace_back(std::move(l), std::move(profile));
  }
  return out;
}

LabelledProfiles readStudyTrials(const session::StudyDatabase& study) {
  LabelledProfiles out;
  for (const auto& trial : study.trials()) {
    if (trial.status != session::TrialStatus::kCompleted || trial.sample_count == 0) continue;
    HapticProfile profile = study.trialProfile(trial.id);
    EntryLabels l;
    l.person = trial.plan.subject;
    l.key = fmt::format("study/{}/trial-{}", study.study().name, trial.id);
    l.skill = trial.plan.skill.empty() ? study.study().skill : trial.plan.skill;
    l.session = fmt::format("{}", trial.plan.session + 1);
    l.mode = std::string(guidance::modeName(trial.plan.mode));
    l.device = profile.metadata().device;
    l.source = fmt::format("study {} trial {}", study.file().string(), trial.id);
    out.emplace_back(std::move(l), std::move(profile));
  }
  return out;
}

}  // namespace hattr::library
