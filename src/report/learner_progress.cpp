#include "hattr/report/learner_progress.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/report/design_analysis.hpp"
#include "hattr/session/study_schedule.hpp"

namespace hattr::report {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kAboutTheSame = 0.05;  // hattr's reading: within ±5 % of the start

/// The mean of the finite values (NaN: none).
double mean(const std::vector<double>& values) {
  double sum = 0.0;
  int n = 0;
  for (const double v : values) {
    if (!std::isfinite(v)) continue;
    sum += v;
    ++n;
  }
  return n == 0 ? kNaN : sum / n;
}

double measure(const DesignTrialScore& s, const char* name) {
  const auto it = s.kinematics.find(name);
  return it == s.kinematics.end() ? kNaN : it->second;
}

/// The one person of the study, or `subject` checked.
const session::SubjectRecord& pickSubject(const session::StudyDatabase& db,
                                          const std::vector<session::SubjectRecord>& subjects, const std::string& subject) {
  std::vector<std::string> ids;
  for (const auto& s : subjects) ids.push_back(s.id);
  if (subject.empty()) {
    HATTR_THROW_UNLESS(subjects.size() == 1, "progress of {}: expected one subject or a subject named, got {} ({})",
                       db.file().string(), subjects.size(), fmt::join(ids, ", "));
    return subjects.front();
  }
  const auto it = std::find_if(subjects.begin(), subjects.end(), [&](const auto& s) { return s.id == subject; });
  HATTR_THROW_UNLESS(it != subjects.end(), "progress of {}: no subject \"{}\"; expected one of {}", db.file().string(),
                     textExcerpt(subject), fmt::join(ids, ", "));
  return *it;
}

/// The subject's completed trials in the order written, scored (analyzeDesign; those in `scored`
/// are not scored again), with their dates.
std::vector<ProgressTrial> scoredTrials(const session::StudyDatabase& db, const std::string& subject,
                                        const std::vector<session::TrialRecord>& records, const ScoreCache* scored) {
  std::map<std::int64_t, const session::TrialRecord*> by_id;
  for (const auto& r : records) by_id[r.id] = &r;
  const bool any = std::any_of(records.begin(), records.end(),
                               [](const auto& r) { return r.status == session::TrialStatus::kCompleted; });
  if (!any) return {};
  const DesignAnalysis analysis = analyzeDesign(db, {.scored = scored, .kinematics_of_scored = true});
  std::vector<ProgressTrial> trials;
  for (const auto* list : {&analysis.scores, &analysis.left_out}) {
    for (const DesignTrialScore& s : *list) {
      if (s.subject != subject) continue;
      const session::TrialRecord& r = *by_id.at(s.trial_id);
      trials.push_back({.trial_id = s.trial_id, .session = s.session,
                        .date = r.started_utc.empty() ? "" : session::localDateOfUtc(r.started_utc).iso(),
                        .phase = s.phase, .skill = session::letterName(s.skill), .trial = s.trial,
                        .guided = s.guided && s.strategy != guidance::modeName(guidance::TrainingMode::kBasic),
                        .disturbed = !s.disturbed.empty(), .shape = s.shape(), .force = s.force(), .score = s.score,
                        .writing_time_s = measure(s, "writing_time_s"), .pen_lifts = measure(s, "pen_lifts"),
                        .velocity_peaks = measure(s, "velocity_peaks")});
    }
  }
  std::sort(trials.begin(), trials.end(), [&](const auto& a, const auto& b) {
    return by_id.at(a.trial_id)->plan.sequence < by_id.at(b.trial_id)->plan.sequence;
  });
  for (std::size_t i = 0; i < trials.size(); ++i) trials[i].number = static_cast<int>(i) + 1;
  return trials;
}

/// Which trials measure the learner: those written alone (or every trial of a plan that has
/// none), not disturbed, with a shape cost.
bool compared(const ProgressTrial& t, bool compares_alone) {
  return (!compares_alone || !t.guided) && !t.disturbed && std::isfinite(t.shape);
}

/// Best and latest of each letter among the compared trials.
void markBestAndLatest(std::vector<ProgressTrial>& trials, bool compares_alone) {
  std::map<std::string, std::size_t> best, latest;
  for (std::size_t i = 0; i < trials.size(); ++i) {
    if (!compared(trials[i], compares_alone)) continue;
    const auto b = best.find(trials[i].skill);
    if (b == best.end() || trials[i].shape < trials[b->second].shape) best[trials[i].skill] = i;
    latest[trials[i].skill] = i;
  }
  for (const auto& [skill, i] : best) trials[i].best = true;
  for (const auto& [skill, i] : latest) trials[i].latest = true;
}

/// Where each letter starts: the first session with compared trials, its baseline trials when it
/// has them (then the session's later trials compare with them), else all of its trials (then
/// that session is the start itself). `start_session`: that session (0: none yet).
struct Start {
  int session = 0;
  bool has_baseline = false;
  std::map<std::string, double> shape;  // by letter
};
Start findStart(const std::vector<ProgressTrial>& trials, bool compares_alone) {
  Start start;
  for (const auto& t : trials) {
    if (compared(t, compares_alone)) {
      start.session = t.session;
      break;
    }
  }
  std::map<std::string, std::vector<double>> baseline, all;
  for (const auto& t : trials) {
    if (t.session != start.session || !compared(t, compares_alone)) continue;
    all[t.skill].push_back(t.shape);
    if (t.phase == session::kPhaseBaseline) baseline[t.skill].push_back(t.shape);
  }
  start.has_baseline = !baseline.empty();
  for (const auto& [skill, values] : all) start.shape[skill] = mean(baseline.contains(skill) ? baseline[skill] : values);
  return start;
}

/// "1 pen lift", "1.5 pen lifts", "0 pen lifts": a mean to one decimal ("" when not a number).
std::string plural(double n, std::string_view one, std::string_view many) {
  if (!std::isfinite(n)) return "";
  std::string number = fmt::format("{:.1f}", n);
  if (number.ends_with(".0")) number.resize(number.size() - 2);
  return fmt::format("{} {}", number, number == "1" ? one : many);
}

/// "8 guided trials and 3 written alone (a, b)", "1 guided trial (a)", "3 trials written alone (a)".
std::string trialsText(const ProgressSession& s, const std::vector<std::string>& letters) {
  const std::string of = fmt::format("{}", fmt::join(letters, ", "));
  const std::string guided = fmt::format("{} guided trial{}", s.guided, s.guided == 1 ? "" : "s");
  if (s.guided > 0 && s.alone > 0) return fmt::format("{} and {} written alone ({})", guided, s.alone, of);
  if (s.guided > 0) return fmt::format("{} ({})", guided, of);
  return fmt::format("{} trial{} written alone ({})", s.alone, s.alone == 1 ? "" : "s", of);
}

/// How the session's shape compares with the start.
std::string changeText(const ProgressSession& s) {
  if (s.is_start) return "this is the starting point";
  if (!std::isfinite(s.change)) return "its letters are not the start's, so it is not compared";
  std::string text = std::abs(s.change) < kAboutTheSame
                         ? std::string("the shape was about the same as at the start")
                         : fmt::format("the shape was {:.0f} % {} the model than at the start",
                                       std::abs(s.change) * 100.0, s.change > 0 ? "closer to" : "further from");
  return s.best_so_far ? text + ", the best so far" : text;
}

/// The session's kinematics in words: "1.1 s a letter, 0 pen lifts, 6.4 speed changes".
std::string kinematicsText(const ProgressSession& s) {
  std::vector<std::string> parts;
  if (std::isfinite(s.writing_time_s)) parts.push_back(fmt::format("{:.1f} s a letter", s.writing_time_s));
  for (std::string part : {plural(s.pen_lifts, "pen lift", "pen lifts"),
                           plural(s.velocity_peaks, "speed change", "speed changes")}) {
    if (!part.empty()) parts.push_back(std::move(part));
  }
  return fmt::format("{}", fmt::join(parts, ", "));
}

/// The session in one plain sentence.
std::string sessionSentence(const ProgressSession& s, const std::vector<std::string>& letters, bool compares_alone) {
  const std::string head = fmt::format("Session {}{}", s.session, s.date.empty() ? "" : " (" + s.date + ")");
  if (s.completed == 0) return head + ": not begun yet.";
  std::string text = fmt::format("{}: {}", head, trialsText(s, letters));
  if (s.completed < s.planned) text += fmt::format(" so far ({} of {} trials)", s.completed, s.planned);
  const bool measured = compares_alone ? s.alone > 0 : s.guided > 0;
  text += measured ? fmt::format("; {}{}", compares_alone ? "written alone, " : "with guidance, ", changeText(s))
                   : "; nothing written alone yet";
  const std::string kinematics = kinematicsText(s);
  return text + (kinematics.empty() ? "" : "; " + kinematics) + ".";
}

/// A session's shape by letter: its compared trials, leaving the baseline out when there are others.
std::map<std::string, double> sessionShapes(const std::vector<const ProgressTrial*>& trials, bool compares_alone) {
  std::map<std::string, std::vector<double>> after, all;
  for (const ProgressTrial* t : trials) {
    if (!compared(*t, compares_alone)) continue;
    all[t->skill].push_back(t->shape);
    if (t->phase != session::kPhaseBaseline) after[t->skill].push_back(t->shape);
  }
  std::map<std::string, double> shapes;
  for (const auto& [skill, values] : all) shapes[skill] = mean(after.contains(skill) ? after[skill] : values);
  return shapes;
}

/// The session's numbers from its completed trials, its change from the start.
void measureSession(ProgressSession& s, const std::vector<const ProgressTrial*>& trials, const Start& start,
                    bool compares_alone) {
  std::vector<double> time, lifts, peaks, changes, shapes;
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
  for (const auto& [skill, shape] : sessionShapes(trials, compares_alone)) {
    shapes.push_back(shape);
    const auto it = start.shape.find(skill);
    if (it != start.shape.end() && it->second > 0.0) changes.push_back((it->second - shape) / it->second);
  }
  s.alone_shape = mean(shapes);
  // The start's session is the start itself, unless it has a baseline and trials after it.
  const bool after_baseline = std::any_of(trials.begin(), trials.end(), [&](const ProgressTrial* t) {
    return compared(*t, compares_alone) && t->phase != session::kPhaseBaseline;
  });
  s.is_start = s.session == start.session && !(start.has_baseline && after_baseline);
  s.change = s.is_start ? kNaN : mean(changes);
}

/// The sessions of the schedule, each measured and put in a sentence. "The best so far": a
/// change from the start of at least kAboutTheSame, above every earlier session's.
void summarizeSessions(LearnerProgress& p, const session::StudyDefinition& study,
                       const std::vector<session::TrialRecord>& records, const Start& start) {
  double best_change = 0.0;
  for (std::size_t k = 0; k < study.schedule.size(); ++k) {
    ProgressSession s{.session = static_cast<int>(k) + 1, .day = study.schedule[k].day};
    s.planned = static_cast<int>(std::count_if(records.begin(), records.end(),
                                               [&](const auto& r) { return r.plan.session == static_cast<int>(k); }));
    std::vector<const ProgressTrial*> trials;
    for (const auto& t : p.trials) {
      if (t.session == s.session) trials.push_back(&t);
    }
    if (!trials.empty()) s.date = trials.front()->date;
    measureSession(s, trials, start, p.compares_alone);
    if (std::isfinite(s.change) && s.change >= kAboutTheSame && s.change > best_change) {
      best_change = s.change;
      s.best_so_far = true;
    }
    s.sentence = sessionSentence(s, p.letters, p.compares_alone);
    p.sessions.push_back(std::move(s));
  }
}

}  // namespace

LearnerProgress learnerProgress(const session::StudyDatabase& db, const std::string& subject_id,
                                const ScoreCache* scored) {
  const auto subjects = db.subjects();
  const session::SubjectRecord& subject = pickSubject(db, subjects, subject_id);
  const auto records = db.trials(subject.id);
  const session::StudyDefinition& study = db.study();

  LearnerProgress p{.study = study.name, .file = db.file(), .learner = session::learnerOf(subject.spec)};
  for (const auto& r : records) {
    const std::string letter = session::letterName(r.plan.skill);
    if (std::find(p.letters.begin(), p.letters.end(), letter) == p.letters.end()) p.letters.push_back(letter);
  }
  if (!subject.mode_order.empty()) {
    p.strategy = guidance::strategyInfo(subject.mode_order.front()).plain_name;
    p.strategy_name = guidance::modeName(subject.mode_order.front());
  }
  p.next = session::scheduleText(session::subjectSchedule(study, records, session::localToday()));
  p.compares_alone = std::any_of(records.begin(), records.end(), [](const auto& r) {
    return !r.plan.view.guidance || r.plan.mode == guidance::TrainingMode::kBasic;
  });
  p.trials = scoredTrials(db, subject.id, records, scored);
  markBestAndLatest(p.trials, p.compares_alone);
  summarizeSessions(p, study, records, findStart(p.trials, p.compares_alone));
  return p;
}

nlohmann::json toJson(const LearnerProgress& p) {
  using nlohmann::json;
  const auto number = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  json sessions = json::array();
  for (const auto& s : p.sessions) {
    sessions.push_back({{"session", s.session}, {"day", s.day}, {"date", s.date}, {"planned", s.planned},
                        {"completed", s.completed}, {"guided", s.guided}, {"alone", s.alone},
                        {"alone_shape", number(s.alone_shape)}, {"is_start", s.is_start}, {"change", number(s.change)},
                        {"best_so_far", s.best_so_far}, {"writing_time_s", number(s.writing_time_s)},
                        {"pen_lifts", number(s.pen_lifts)}, {"velocity_peaks", number(s.velocity_peaks)},
                        {"sentence", s.sentence}});
  }
  json trials = json::array();
  for (const auto& t : p.trials) {
    trials.push_back({{"number", t.number}, {"trial_id", t.trial_id}, {"session", t.session}, {"date", t.date},
                      {"phase", t.phase}, {"letter", t.skill}, {"trial", t.trial}, {"guided", t.guided},
                      {"disturbed", t.disturbed}, {"shape", number(t.shape)}, {"force", number(t.force)},
                      {"writing_time_s", number(t.writing_time_s)}, {"pen_lifts", number(t.pen_lifts)},
                      {"velocity_peaks", number(t.velocity_peaks)}, {"best", t.best}, {"latest", t.latest}});
  }
  return {{"study", p.study},         {"file", p.file.string()},         {"learner", p.learner.code},
          {"letters", p.letters},     {"strategy", p.strategy},          {"strategy_name", p.strategy_name},
          {"next", p.next},           {"compares_alone", p.compares_alone}, {"sessions", sessions},
          {"trials", trials}};
}

}  // namespace hattr::report
