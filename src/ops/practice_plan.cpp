#include "hattr/ops/practice_plan.hpp"

#include <algorithm>
#include <set>

#include <fmt/format.h>

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
    problems.push_back("retention: it is made of check trials; with no check trials, set retention after 0 days");
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

std::string letterList(const std::vector<std::string>& letters) {
  std::string out;
  for (const auto& l : letters) out += (out.empty() ? "" : ", ") + l;
  return out;
}

}  // namespace

session::StudyDefinition practicePlanStudy(const PracticePlanOptions& options) {
  std::vector<std::string> problems;
  try {
    session::checkLearner(options.learner);
  } catch (const InputError& e) {
    const std::string text = e.what();
    for (std::size_t at = text.find("\n  - "); at != std::string::npos;) {
      const std::size_t next = text.find("\n  - ", at + 1);
      problems.push_back("learner " + text.substr(at + 5, next == std::string::npos ? next : next - at - 5));
      at = next;
    }
  }
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
  plan["name"] = fmt::format("Practice of {} for {}", letterList(letters), options.learner.code);
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
  std::filesystem::create_directories(dir);
  for (int n = 1;; ++n) {
    const std::filesystem::path file = dir / fmt::format("plan-{}.sqlite", n);
    if (std::filesystem::exists(file)) continue;
    (void)session::StudyDatabase::create(file, study);
    return file;
  }
}

std::vector<PracticePlanSummary> listPracticePlans(const std::filesystem::path& folder, const session::LocalDate& today,
                                                   std::vector<std::string>* skipped) {
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  std::error_code missing;
  for (const auto& learner : fs::directory_iterator(folder, missing)) {
    if (!learner.is_directory()) continue;
    for (const auto& entry : fs::directory_iterator(learner.path())) {
      const std::string name = entry.path().filename().string();
      if (name.starts_with("plan-") && name.ends_with(".sqlite")) files.push_back(entry.path());
    }
  }
  std::vector<PracticePlanSummary> plans;
  for (const fs::path& file : files) {
    try {
      const auto db = session::StudyDatabase::open(file, session::OpenMode::kReadOnly);
      const auto subjects = db.subjects();
      HATTR_THROW_UNLESS(subjects.size() == 1 && subjects.front().spec.participant == "person",
                         "{}: not a practice plan (one learner)", file.string());
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
      plans.push_back(std::move(p));
    } catch (const Error& e) {
      if (skipped != nullptr) skipped->push_back(e.what());
    }
  }
  // By learner, then by plan number (plan-10 after plan-9).
  const auto number = [](const fs::path& f) { return std::stoi(f.stem().string().substr(5)); };
  std::sort(plans.begin(), plans.end(), [&](const auto& a, const auto& b) {
    if (a.learner.code != b.learner.code) return a.learner.code < b.learner.code;
    return number(a.file) < number(b.file);
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
