#include "hattr/ops/practice_plan.hpp"

#include <algorithm>
#include <charconv>
#include <set>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/session/study_database.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/sim/glyph.hpp"

namespace hattr::ops {
namespace {

using nlohmann::json;

/// A number of the options outside its range, as a problem line.
void checkRange(std::vector<std::string>& problems, const char* what, double value, double lo, double hi) {
  if (value >= lo && value <= hi) return;
  problems.push_back(fmt::format("{}: expected {} to {}, got {}", what, lo, hi, value));
}

/// Every problem of the options but the learner's and the letters', one a line.
std::vector<std::string> optionProblems(const PracticePlanOptions& o) {
  std::vector<std::string> problems;
  checkRange(problems, "sessions", o.sessions, 1, 60);
  checkRange(problems, "trials per session", o.trials_per_session, 1, 100);
  checkRange(problems, "check trials", o.check_trials, 0, 20);
  checkRange(problems, "days between sessions", o.days_between, 0, 30);
  checkRange(problems, "retention after (days)", o.retention_after_days, 0, 90);
  checkRange(problems, "rest (s)", o.rest_s, 0.0, 600.0);
  if (o.retention_after_days > 0 && o.check_trials == 0) {
    problems.push_back(fmt::format("retention after {} days: it is made of check trials; expected check trials above 0 "
                                   "(or retention after 0 days), got 0 check trials",
                                   o.retention_after_days));
  }
  if (guidance::isMentored(o.strategy)) {
    problems.push_back(fmt::format("strategy {}: a mentored strategy needs a live expert; a practice plan uses the "
                                   "simulated expert's model letter",
                                   guidance::modeName(o.strategy)));
  }
  if (o.letters.empty()) problems.push_back("letters: expected at least one letter");
  return problems;
}

/// The letters' glyphs: skill (the glyph's name) -> how the study names its expert. Problems
/// for a letter not found or given twice.
std::vector<std::pair<std::string, std::string>> letterSkills(const std::vector<std::string>& letters,
                                                              std::vector<std::string>& problems) {
  std::vector<std::pair<std::string, std::string>> skills;
  std::set<std::string> seen;
  for (const std::string& letter : letters) {
    try {
      const sim::Glyph glyph = sim::findGlyph(letter);
      const bool file = letter.find('/') != std::string::npos || letter.ends_with(".json");
      if (!seen.insert(glyph.name).second) {
        problems.push_back(fmt::format("letters: \"{}\" given twice", textExcerpt(letter)));
        continue;
      }
      skills.emplace_back(glyph.name, file ? std::filesystem::absolute(letter).string() : glyph.name);
    } catch (const InputError&) {
      problems.push_back(fmt::format("letters: \"{}\": not a letter of the library or a glyph file", textExcerpt(letter)));
    }
  }
  return skills;
}

json block(std::string_view phase, const std::string& skill, int trials) {
  json b{{"phase", phase}, {"skill", skill}, {"trials", trials}};
  if (phase == session::kPhaseTraining) b["strategy"] = "group";
  if (phase == session::kPhaseBaseline) b["show_reference"] = true;
  return b;
}

/// The schedule: the sessions' days and blocks (see the header).
json planSessions(const PracticePlanOptions& o, const std::vector<std::pair<std::string, std::string>>& skills) {
  json sessions = json::array();
  for (int k = 0; k < o.sessions; ++k) {
    json blocks = json::array();
    if (k == 0 && o.check_trials > 0) {
      for (const auto& [skill, _] : skills) blocks.push_back(block(session::kPhaseBaseline, skill, o.check_trials));
    }
    for (const auto& [skill, _] : skills) {
      blocks.push_back(block(session::kPhaseTraining, skill, o.trials_per_session));
      if (o.check_trials > 0) blocks.push_back(block(session::kPhasePostTest, skill, o.check_trials));
    }
    sessions.push_back({{"day", k * o.days_between}, {"blocks", blocks}});
  }
  if (o.retention_after_days > 0) {
    json blocks = json::array();
    for (const auto& [skill, _] : skills) blocks.push_back(block(session::kPhaseRetention, skill, o.check_trials));
    sessions.push_back({{"day", (o.sessions - 1) * o.days_between + o.retention_after_days}, {"blocks", blocks}});
  }
  return sessions;
}

}  // namespace

session::StudyDefinition practicePlanStudy(const PracticePlanOptions& options) {
  std::vector<std::string> problems;
  for (const auto& p : session::learnerProblems(options.learner)) problems.push_back("learner " + p);
  for (auto& p : optionProblems(options)) problems.push_back(std::move(p));
  const auto skills = letterSkills(options.letters, problems);
  if (!problems.empty()) {
    std::string message = fmt::format("practice plan: {} problem{}:", problems.size(), problems.size() == 1 ? "" : "s");
    for (const auto& p : problems) message += "\n  - " + p;
    throw InputError(message);
  }

  // The `learner` design, made for this learner, these letters and this strategy.
  json plan = json::parse(session::exampleDesign("learner").json);
  std::vector<std::string> letters;
  for (const auto& [skill, _] : skills) letters.push_back(session::letterName(skill));
  plan["name"] = fmt::format("Practice of {} for {}", fmt::join(letters, ", "), options.learner.code);
  plan["skill"] = skills.front().first;
  plan["experts"] = json::object();
  for (const auto& [skill, expert] : skills) plan["experts"][skill] = expert;
  plan["protocol"]["rest_s"] = options.rest_s;
  plan["device"] = options.device;
  json subject{{"id", options.learner.code}, {"participant", "person"}};
  subject["options"] = {{"learner", session::learnerOptions(options.learner)}};
  plan["groups"] = json::array({{{"name", "learner"},
                                 {"strategies", json::array({guidance::strategyName(options.strategy)})},
                                 {"subjects", json::array({subject})}}});
  plan["sessions"] = planSessions(options, skills);
  return session::parseStudy(plan.dump(), "practice plan", std::filesystem::current_path());
}

std::filesystem::path createPracticePlan(const std::filesystem::path& folder, const PracticePlanOptions& options) {
  session::StudyDefinition study = practicePlanStudy(options);
  sim::recordNamedExperts(study);
  (void)session::checkExpertsRenderable(study);
  const std::filesystem::path dir = folder / options.learner.code;
  std::error_code failed;
  std::filesystem::create_directories(dir, failed);
  HATTR_THROW_UNLESS(!failed && std::filesystem::is_directory(dir),
                     "practice plan: the learner's folder {}: expected a folder that can be made and written, got {}",
                     dir.string(), failed ? failed.message() : "a file of that name");
  for (int n = 1;; ++n) {
    const std::filesystem::path file = dir / fmt::format("plan-{}.sqlite", n);
    if (std::filesystem::exists(file)) continue;
    (void)session::StudyDatabase::create(file, study);
    return file;
  }
}

namespace {

/// N of a plan file's name "plan-N.sqlite" (N a whole number below a million), or 0 for any other.
int planNumber(const std::string& file_name) {
  constexpr std::string_view kPrefix = "plan-", kSuffix = ".sqlite";
  if (!file_name.starts_with(kPrefix) || !file_name.ends_with(kSuffix)) return 0;
  const std::string_view digits(file_name.data() + kPrefix.size(), file_name.size() - kPrefix.size() - kSuffix.size());
  int n = 0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), n);
  const bool whole = error == std::errc() && end == digits.data() + digits.size() && !digits.empty();
  return whole && n > 0 && n < 1'000'000 ? n : 0;
}

/// The plan files of a practice folder: FOLDER/<code>/plan-N.sqlite. InputError for a folder
/// that is not there or cannot be read; a learner's folder that cannot be read is skipped.
std::vector<std::filesystem::path> planFiles(const std::filesystem::path& folder, std::vector<std::string>* skipped) {
  namespace fs = std::filesystem;
  std::error_code failed;
  HATTR_THROW_UNLESS(fs::is_directory(folder, failed), "practice folder {}: expected a folder, got {}", folder.string(),
                     fs::exists(folder) ? "a file" : "nothing there");
  std::vector<fs::path> files;
  for (fs::directory_iterator learner(folder, failed), end; !failed && learner != end; learner.increment(failed)) {
    if (!learner->is_directory(failed)) continue;
    std::error_code unreadable;
    for (fs::directory_iterator entry(learner->path(), unreadable); !unreadable && entry != end;
         entry.increment(unreadable)) {
      if (planNumber(entry->path().filename().string()) > 0) files.push_back(entry->path());
    }
    if (unreadable && skipped != nullptr) skipped->push_back(fmt::format("{}: {}", learner->path().string(), unreadable.message()));
  }
  HATTR_THROW_UNLESS(!failed, "practice folder {}: cannot be read: {}", folder.string(), failed.message());
  return files;
}

}  // namespace

PracticePlanSummary summarizePracticePlan(const std::filesystem::path& file, const session::LocalDate& today) {
  const auto db = session::StudyDatabase::open(file, session::OpenMode::kReadOnly);
  const auto subjects = db.subjects();
  const bool one_person = subjects.size() == 1 && subjects.front().spec.participant == "person";
  HATTR_THROW_UNLESS(one_person, "{}: expected a practice plan (one learner, a person), got {} subjects{}", file.string(),
                     subjects.size(), subjects.size() == 1 ? " (a " + subjects.front().spec.participant + " one)" : "");
  PracticePlanSummary p{.file = file, .learner = session::learnerOf(subjects.front().spec), .name = db.study().name};
  for (const auto& block : db.study().schedule.front().blocks) {
    const std::string letter = session::letterName(block.skill);
    if (std::find(p.letters.begin(), p.letters.end(), letter) == p.letters.end()) p.letters.push_back(letter);
  }
  p.strategy = db.study().groups.front().strategies.front();
  const auto trials = db.trials(subjects.front().id);
  p.trials_total = static_cast<int>(trials.size());
  p.trials_completed = static_cast<int>(std::count_if(
      trials.begin(), trials.end(), [](const auto& t) { return t.status == session::TrialStatus::kCompleted; }));
  p.schedule = session::subjectSchedule(db.study(), trials, today);
  return p;
}

std::vector<PracticePlanSummary> listPracticePlans(const std::filesystem::path& folder, const session::LocalDate& today,
                                                   std::vector<std::string>* skipped) {
  std::vector<PracticePlanSummary> plans;
  for (const auto& file : planFiles(folder, skipped)) {
    try {
      plans.push_back(summarizePracticePlan(file, today));
    } catch (const Error& e) {
      if (skipped != nullptr) skipped->push_back(e.what());
    }
  }
  // By learner, then by plan number (plan-10 after plan-9).
  std::sort(plans.begin(), plans.end(), [](const auto& a, const auto& b) {
    if (a.learner.code != b.learner.code) return a.learner.code < b.learner.code;
    return planNumber(a.file.filename().string()) < planNumber(b.file.filename().string());
  });
  return plans;
}

json toJson(const PracticePlanSummary& p) {
  return {{"file", p.file.string()},
          {"learner", p.learner.code},
          {"name", p.name},
          {"letters", p.letters},
          {"strategy", guidance::strategyName(p.strategy)},
          {"plain_strategy", guidance::strategyInfo(p.strategy).plain_name},
          {"trials_total", p.trials_total},
          {"trials_completed", p.trials_completed},
          {"next", session::scheduleText(p.schedule)}};
}

}  // namespace hattr::ops
