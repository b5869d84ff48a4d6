#include "hattr/report/learner_progress.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/report/design_analysis.hpp"
#include "hattr/session/study_schedule.hpp"

namespace hattr::report {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kAboutTheSame = 0.05;  // hattr's reading: within ±5 % of the start

double mean(const std::vector<double>& values) {
  if (values.empty()) return kNaN;
  double sum = 0.0;
  for (const double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

double measure(const DesignTrialScore& s, const char* name) {
  const auto it = s.kinematics.find(name);
  return it == s.kinematics.end() ? kNaN : it->second;
}

/// The one person of the study, or `subject` checked.
const session::SubjectRecord& pickSubject(const std::vector<session::SubjectRecord>& subjects, const std::string& subject) {
  if (subject.empty()) {
    HATTR_THROW_UNLESS(subjects.size() == 1, "progress: the study has {} subjects: name one (--subject)", subjects.size());
    return subjects.front();
  }
  const auto it = std::find_if(subjects.begin(), subjects.end(), [&](const auto& s) { return s.id == subject; });
  HATTR_THROW_UNLESS(it != subjects.end(), "progress: no subject \"{}\" in the study", textExcerpt(subject));
  return *it;
}

/// The subject's completed trials in the order written, scored (analyzeDesign), with their dates.
std::vector<ProgressTrial> scoredTrials(const session::StudyDatabase& db, const std::string& subject,
                                        const std::vector<session::TrialRecord>& records) {
  std::map<std::int64_t, const session::TrialRecord*> by_id;
  for (const auto& r : records) by_id[r.id] = &r;
  const bool any = std::any_of(records.begin(), records.end(),
                               [](const auto& r) { return r.status == session::TrialStatus::kCompleted; });
  if (!any) return {};
  const DesignAnalysis analysis = analyzeDesign(db);
  std::vector<ProgressTrial> trials;
  for (const DesignTrialScore& s : analysis.scores) {
    if (s.subject != subject) continue;
    const session::TrialRecord& r = *by_id.at(s.trial_id);
    trials.push_back({.trial_id = s.trial_id, .session = s.session,
                      .date = r.started_utc.empty() ? "" : session::localDateOfUtc(r.started_utc).iso(),
                      .phase = s.phase, .skill = session::letterName(s.skill), .trial = s.trial,
                      .guided = s.guided && s.strategy != guidance::modeName(guidance::TrainingMode::kBasic),
                      .shape = s.shape(), .force = s.force(),
                      .writing_time_s = measure(s, "writing_time_s"), .pen_lifts = measure(s, "pen_lifts"),
                      .velocity_peaks = measure(s, "velocity_peaks")});
  }
  std::stable_sort(trials.begin(), trials.end(), [&](const auto& a, const auto& b) {
    return by_id.at(a.trial_id)->plan.sequence < by_id.at(b.trial_id)->plan.sequence;
  });
  for (std::size_t i = 0; i < trials.size(); ++i) trials[i].number = static_cast<int>(i) + 1;
  return trials;
}

/// Which trials measure the learner: those written alone, or every trial of a plan that has none.
bool compared(const ProgressTrial& t, bool plan_has_alone) { return !plan_has_alone || !t.guided; }

/// Best and latest of each letter among the compared trials.
void markBestAndLatest(std::vector<ProgressTrial>& trials, bool plan_has_alone) {
  std::map<std::string, std::size_t> best, latest;
  for (std::size_t i = 0; i < trials.size(); ++i) {
    if (!compared(trials[i], plan_has_alone)) continue;
    const auto b = best.find(trials[i].skill);
    if (b == best.end() || trials[i].shape < trials[b->second].shape) best[trials[i].skill] = i;
    latest[trials[i].skill] = i;
  }
  for (const auto& [skill, i] : best) trials[i].best = true;
  for (const auto& [skill, i] : latest) trials[i].latest = true;
}

/// Each letter's shape at the start: the first session with compared trials, its baseline
/// trials when it has them.
std::map<std::string, double> startShapes(const std::vector<ProgressTrial>& trials, bool plan_has_alone) {
  int first = 0;
  for (const auto& t : trials) {
    if (compared(t, plan_has_alone)) {
      first = t.session;
      break;
    }
  }
  std::map<std::string, std::vector<double>> baseline, all;
  for (const auto& t : trials) {
    if (t.session != first || !compared(t, plan_has_alone)) continue;
    all[t.skill].push_back(t.shape);
    if (t.phase == session::kPhaseBaseline) baseline[t.skill].push_back(t.shape);
  }
  std::map<std::string, double> start;
  for (const auto& [skill, values] : all) start[skill] = mean(baseline.contains(skill) ? baseline[skill] : values);
  return start;
}

/// "1 pen lift", "1.5 pen lifts", "0 pen lifts": a mean to one decimal.
std::string plural(double n, std::string_view one, std::string_view many) {
  std::string number = fmt::format("{:.1f}", n);
  if (number.ends_with(".0")) number.resize(number.size() - 2);
  return fmt::format("{} {}", number, number == "1" ? one : many);
}

/// "8 guided trials and 3 written alone (a, b)", "1 guided trial (a)", "3 trials written alone (a)".
std::string trialsText(const ProgressSession& s, const std::vector<std::string>& letters) {
  std::string of;
  for (const auto& l : letters) of += (of.empty() ? "" : ", ") + l;
  const std::string guided = fmt::format("{} guided trial{}", s.guided, s.guided == 1 ? "" : "s");
  if (s.guided > 0 && s.alone > 0) return fmt::format("{} and {} written alone ({})", guided, s.alone, of);
  if (s.guided > 0) return fmt::format("{} ({})", guided, of);
  return fmt::format("{} trial{} written alone ({})", s.alone, s.alone == 1 ? "" : "s", of);
}

/// How the session's shape compares with the start.
std::string changeText(const ProgressSession& s) {
  std::string text;
  if (!std::isfinite(s.change)) return "this is the starting point";
  if (std::abs(s.change) < kAboutTheSame) {
    text = "the shape was about the same as at the start";
  } else {
    text = fmt::format("the shape was {:.0f} % {} the model than at the start", std::abs(s.change) * 100.0,
                       s.change > 0 ? "closer to" : "further from");
  }
  return s.best_so_far ? text + ", the best so far" : text;
}

/// The session in one plain sentence.
std::string sessionSentence(const ProgressSession& s, const std::vector<std::string>& letters, bool plan_has_alone) {
  const std::string head = fmt::format("Session {}{}", s.session, s.date.empty() ? "" : " (" + s.date + ")");
  if (s.completed == 0) return head + ": not begun yet.";
  std::string text = fmt::format("{}: {}", head, trialsText(s, letters));
  if (s.completed < s.planned) text += fmt::format(" so far ({} of {} trials)", s.completed, s.planned);
  const bool measured = plan_has_alone ? s.alone > 0 : s.guided > 0;
  text += measured ? fmt::format("; {}{}", plan_has_alone ? "written alone, " : "with guidance, ", changeText(s))
                   : "; nothing written alone yet";
  if (std::isfinite(s.writing_time_s)) {
    text += fmt::format("; {:.1f} s a letter, {}, {}", s.writing_time_s, plural(s.pen_lifts, "pen lift", "pen lifts"),
                        plural(s.velocity_peaks, "speed change", "speed changes"));
  }
  return text + ".";
}

/// A session's shape by letter: its compared trials, leaving the baseline out when there are others.
std::map<std::string, double> sessionShapes(const std::vector<const ProgressTrial*>& trials, bool plan_has_alone) {
  std::map<std::string, std::vector<double>> after, all;
  for (const ProgressTrial* t : trials) {
    if (!compared(*t, plan_has_alone)) continue;
    all[t->skill].push_back(t->shape);
    if (t->phase != session::kPhaseBaseline) after[t->skill].push_back(t->shape);
  }
  std::map<std::string, double> shapes;
  for (const auto& [skill, values] : all) shapes[skill] = mean(after.contains(skill) ? after[skill] : values);
  return shapes;
}

/// The session's numbers from its completed trials, its change from the start.
void measureSession(ProgressSession& s, const std::vector<const ProgressTrial*>& trials,
                    const std::map<std::string, double>& start, bool plan_has_alone, bool is_start) {
  std::vector<double> time, lifts, peaks, changes, shapes_all;
  for (const ProgressTrial* t : trials) {
    (t->guided ? s.guided : s.alone) += 1;
    time.push_back(t->writing_time_s);
    lifts.push_back(t->pen_lifts);
    peaks.push_back(t->velocity_peaks);
  }
  s.completed = s.guided + s.alone;
  s.writing_time_s = mean(time);
  s.pen_lifts = mean(lifts);
  s.velocity_peaks = mean(peaks);
  const auto shapes = sessionShapes(trials, plan_has_alone);
  for (const auto& [skill, shape] : shapes) {
    shapes_all.push_back(shape);
    const auto it = start.find(skill);
    if (it != start.end() && it->second > 0.0) changes.push_back((it->second - shape) / it->second);
  }
  s.alone_shape = mean(shapes_all);
  // The start's own session compares with its baseline only when it has trials after it.
  const bool only_baseline = std::all_of(trials.begin(), trials.end(), [&](const ProgressTrial* t) {
    return !compared(*t, plan_has_alone) || t->phase == session::kPhaseBaseline;
  });
  s.change = is_start && only_baseline ? kNaN : mean(changes);
}

/// The sessions of the schedule, each measured and put in a sentence.
void summarizeSessions(LearnerProgress& p, const session::StudyDefinition& study,
                       const std::vector<session::TrialRecord>& records, const std::map<std::string, double>& start,
                       bool plan_has_alone) {
  double best = std::numeric_limits<double>::infinity();
  bool start_seen = false;
  for (std::size_t k = 0; k < study.schedule.size(); ++k) {
    ProgressSession s{.session = static_cast<int>(k) + 1, .day = study.schedule[k].day};
    s.planned = static_cast<int>(std::count_if(records.begin(), records.end(),
                                               [&](const auto& r) { return r.plan.session == static_cast<int>(k); }));
    std::vector<const ProgressTrial*> trials;
    for (const auto& t : p.trials) {
      if (t.session == s.session) trials.push_back(&t);
    }
    if (!trials.empty()) s.date = trials.front()->date;
    const bool has_compared = std::any_of(trials.begin(), trials.end(),
                                          [&](const ProgressTrial* t) { return compared(*t, plan_has_alone); });
    measureSession(s, trials, start, plan_has_alone, has_compared && !start_seen);
    start_seen = start_seen || has_compared;
    if (std::isfinite(s.alone_shape) && s.alone_shape < best) {
      best = s.alone_shape;
      s.best_so_far = std::isfinite(s.change);  // the start is not "the best so far"
    }
    s.sentence = sessionSentence(s, p.letters, plan_has_alone);
    p.sessions.push_back(std::move(s));
  }
}

}  // namespace

LearnerProgress learnerProgress(const session::StudyDatabase& db, const std::string& subject_id) {
  const auto subjects = db.subjects();
  const session::SubjectRecord& subject = pickSubject(subjects, subject_id);
  const auto records = db.trials(subject.id);
  const session::StudyDefinition& study = db.study();

  LearnerProgress p{.study = study.name, .file = db.file(), .learner = session::learnerOf(subject.spec)};
  for (const auto& r : records) {
    const std::string letter = session::letterName(r.plan.skill);
    if (std::find(p.letters.begin(), p.letters.end(), letter) == p.letters.end()) p.letters.push_back(letter);
  }
  const auto& strategies = subject.mode_order;
  if (!strategies.empty()) {
    p.strategy = guidance::strategyInfo(strategies.front()).plain_name;
    p.strategy_name = guidance::modeName(strategies.front());
  }
  p.next = session::scheduleText(session::subjectSchedule(study, records, session::localToday()));

  const bool plan_has_alone =
      std::any_of(records.begin(), records.end(), [](const auto& r) { return !r.plan.view.guidance || r.plan.mode == guidance::TrainingMode::kBasic; });
  p.trials = scoredTrials(db, subject.id, records);
  markBestAndLatest(p.trials, plan_has_alone);
  summarizeSessions(p, study, records, startShapes(p.trials, plan_has_alone), plan_has_alone);
  return p;
}

nlohmann::json toJson(const LearnerProgress& p) {
  using nlohmann::json;
  const auto number = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  json sessions = json::array();
  for (const auto& s : p.sessions) {
    sessions.push_back({{"session", s.session}, {"day", s.day}, {"date", s.date}, {"planned", s.planned},
                        {"completed", s.completed}, {"guided", s.guided}, {"alone", s.alone},
                        {"alone_shape", number(s.alone_shape)}, {"change", number(s.change)},
                        {"best_so_far", s.best_so_far}, {"writing_time_s", number(s.writing_time_s)},
                        {"pen_lifts", number(s.pen_lifts)}, {"velocity_peaks", number(s.velocity_peaks)},
                        {"sentence", s.sentence}});
  }
  json trials = json::array();
  for (const auto& t : p.trials) {
    trials.push_back({{"number", t.number}, {"trial_id", t.trial_id}, {"session", t.session}, {"date", t.date},
                      {"phase", t.phase}, {"letter", t.skill}, {"trial", t.trial}, {"guided", t.guided},
                      {"shape", number(t.shape)}, {"force", number(t.force)},
                      {"writing_time_s", number(t.writing_time_s)}, {"pen_lifts", number(t.pen_lifts)},
                      {"velocity_peaks", number(t.velocity_peaks)}, {"best", t.best}, {"latest", t.latest}});
  }
  return {{"study", p.study},       {"file", p.file.string()}, {"learner", p.learner.code},
          {"letters", p.letters},   {"strategy", p.strategy},  {"strategy_name", p.strategy_name},
          {"next", p.next},         {"sessions", sessions},    {"trials", trials}};
}

}  // namespace hattr::report
