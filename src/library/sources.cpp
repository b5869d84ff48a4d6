// Labelled profiles from an SVC2004 folder and from a study's completed trials.

#include "hattr/library/sources.hpp"

#include <algorithm>
#include <regex>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/guidance/training_guidance.hpp"

namespace hattr::library {

LabelledProfiles readSvc2004Folder(const std::filesystem::path& folder, const io::TabletCalibration& calibration) {
  HATTR_THROW_UNLESS(std::filesystem::is_directory(folder),
                     "{}: not a folder; expected the SVC2004 Task 2 folder of U<writer>S<signature>.TXT files",
                     folder.string());
  // The files in writer, then signature order.
  static const std::regex kName(R"(U([0-9]+)S([0-9]+)\.TXT)");
  std::vector<std::tuple<int, int, std::filesystem::path>> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    std::smatch m;
    const std::string name = entry.path().filename().string();
    if (!entry.is_regular_file() || !std::regex_match(name, m, kName)) continue;
    const auto number = [&](const std::string& digits) {
      HATTR_THROW_UNLESS(digits.size() <= 6, "{}: number {} in the name; expected at most 6 digits",
                         entry.path().string(), digits);
      return std::stoi(digits);
    };
    const int writer = number(m[1]);
    const int signature = number(m[2]);
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
