// hattr study push: a study's completed trials copied from one store into another (a station
// that ran offline on SQLite, into the lab's PostgreSQL study), idempotent, refusing conflicts.

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/session/study_database.hpp"
#include "sql_connection.hpp"
#include "study_postgres.hpp"

namespace hattr::session {
namespace {

using detail::SqlConnection;
using detail::Statement;

/// The study's definition without where its experts came from (each station's own paths).
std::string definitionWithoutExpertPaths(SqlConnection& db) {
  Statement s(db, "SELECT definition FROM study WHERE id = 1");
  HATTR_THROW_UNLESS(s.step(), "{}: the study table is empty", db.location());
  nlohmann::json definition = nlohmann::json::parse(s.text(0));
  definition.erase("experts");
  return definition.dump();
}

/// Rows of a query, each as one text line (for comparing two stores' plans).
std::vector<std::string> rowsAsText(SqlConnection& db, std::string_view sql, int text_columns, int integer_columns) {
  std::vector<std::string> rows;
  Statement s(db, sql);
  while (s.step()) {
    std::string row;
    for (int c = 0; c < text_columns; ++c) row += s.text(c) + '\x1f';
    for (int c = 0; c < integer_columns; ++c) row += fmt::format("{}\x1f", s.integer(text_columns + c));
    rows.push_back(std::move(row));
  }
  return rows;
}

/// What makes two studies one: the definition, the experts, the subjects and the plan.
std::vector<std::string> differences(SqlConnection& from, SqlConnection& to) {
  std::vector<std::string> found;
  if (definitionWithoutExpertPaths(from) != definitionWithoutExpertPaths(to)) found.push_back("the study definitions differ");
  constexpr std::string_view kExperts = "SELECT skill, profile_csv FROM experts ORDER BY skill";
  if (rowsAsText(from, kExperts, 2, 0) != rowsAsText(to, kExperts, 2, 0)) found.push_back("the expert references differ");
  constexpr std::string_view kSubjects = "SELECT id, mode_order, spec, position FROM subjects ORDER BY id";
  if (rowsAsText(from, kSubjects, 3, 1) != rowsAsText(to, kSubjects, 3, 1)) {
    found.push_back("the subjects or their mode orders differ");
  }
  constexpr std::string_view kPlan =
      "SELECT subject, mode, phase, sequence, trial_index, show_reference, guidance FROM trials ORDER BY subject, sequence";
  if (rowsAsText(from, kPlan, 3, 4) != rowsAsText(to, kPlan, 3, 4)) found.push_back("the trial plans differ");
  return found;
}

/// The source's completed trials with their stored samples, one at a time.
constexpr std::string_view kCompletedTrials =
    "SELECT t.id, t.subject, t.sequence, t.attempts, t.interruptions, t.started_utc, t.ended_utc, t.outcome, "
    "t.metadata, t.disturbed, s.raw_pressure, s.raw_tilt, s.sample_count, s.data, s.encoding "
    "FROM trials t JOIN samples s ON s.trial = t.id WHERE t.status = 'completed' ORDER BY t.subject, t.sequence";

/// The same trial in the target: its id, whether completed, and its stored samples when so.
constexpr std::string_view kTargetTrial =
    "SELECT t.id, t.status, t.metadata, s.sample_count, s.data, s.encoding FROM trials t "
    "LEFT JOIN samples s ON s.trial = t.id WHERE t.subject = ? AND t.sequence = ?";

/// A refused push: every conflict is said (the first five listed), and nothing is written.
[[noreturn]] void refusePush(const SqlConnection& from, const SqlConnection& to,
                             const std::vector<std::string>& conflicts) {
  std::string list;
  for (std::size_t i = 0; i < conflicts.size() && i < 5; ++i) list += "\n  " + conflicts[i];
  if (conflicts.size() > 5) list += fmt::format("\n  ... and {} more", conflicts.size() - 5);
  throw InputError(fmt::format("study push from {} to {}: refused, nothing written: {} conflict{}:{}", from.location(),
                               to.location(), conflicts.size(), conflicts.size() == 1 ? "" : "s", list));
}

/// The same trial in the target: missing (-1), pending (0), completed the same (1) or
/// differently (2) as the source's row `trials` is on; `target_id` is its id when it is there.
int targetTrialState(SqlConnection& to, const Statement& trials, const std::string& subject, std::int64_t sequence,
                     std::int64_t& target_id) {
  Statement target(to, kTargetTrial);
  target.bind(1, subject).bind(2, sequence);
  if (!target.step()) return -1;
  target_id = target.integer(0);
  if (target.text(1) != "completed") return 0;
  const bool same = target.text(2) == trials.text(8) && target.integer(3) == trials.integer(12) &&
                    target.blob(4) == trials.blob(13) && target.text(5) == trials.text(14);
  return same ? 1 : 2;
}

/// The check pass's conflict for a subject a station (PostgreSQL) holds a live lease on.
void noteRunningStation(SqlConnection& to, const std::string& subject, std::int64_t sequence,
                        std::vector<std::string>& conflicts) {
  Statement lease(to, "SELECT host, pid FROM subject_leases WHERE subject = ? AND expires_at > clock_timestamp()");
  lease.bind(1, subject);
  if (lease.step()) {
    conflicts.push_back(fmt::format("subject {} trial {}: a station (process {} on {}) is running this subject now",
                                    subject, sequence, lease.integer(1), lease.text(0)));
  }
}

/// Writes the source's trial (the row `trials` is on) into the target's trial `target_id`: the
/// trial as the source stored it, and its disturbed attempts. False, with nothing written,
/// when the target's trial was completed meanwhile.
bool copyTrial(SqlConnection& from, SqlConnection& to, const Statement& trials, std::int64_t target_id) {
  Statement trial(to, "UPDATE trials SET status = 'completed', attempts = ?, interruptions = ?, started_utc = ?, "
                      "ended_utc = ?, outcome = ?, metadata = ?, disturbed = ? WHERE id = ? AND status != 'completed'");
  trial.bind(1, trials.integer(3)).bind(2, trials.integer(4)).bind(3, trials.text(5)).bind(4, trials.text(6))
      .bind(5, trials.text(7)).bind(6, trials.text(8));
  if (trials.isNull(9)) {
    trial.bindNull(7);
  } else {
    trial.bind(7, trials.text(9));
  }
  trial.bind(8, target_id).run();
  if (trial.changes() != 1) return false;  // the caller notes the conflict
  Statement samples(to, "INSERT INTO samples (trial, raw_pressure, raw_tilt, sample_count, data, encoding) "
                        "VALUES (?, ?, ?, ?, ?, ?) ON CONFLICT (trial) DO UPDATE SET raw_pressure = "
                        "excluded.raw_pressure, raw_tilt = excluded.raw_tilt, sample_count = excluded.sample_count, "
                        "data = excluded.data, encoding = excluded.encoding");
  samples.bind(1, target_id).bind(2, trials.integer(10)).bind(3, trials.integer(11)).bind(4, trials.integer(12))
      .bindBlob(5, trials.blob(13)).bind(6, trials.text(14)).run();
  Statement attempts(from, "SELECT reason, ended_utc, metadata, raw_pressure, raw_tilt, sample_count, data, encoding "
                           "FROM disturbed_attempts WHERE trial = ? ORDER BY id");
  attempts.bind(1, trials.integer(0));
  while (attempts.step()) {
    Statement copy(to, "INSERT INTO disturbed_attempts (trial, reason, ended_utc, metadata, raw_pressure, raw_tilt, "
                       "sample_count, data, encoding) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)");
    copy.bind(1, target_id).bind(2, attempts.text(0)).bind(3, attempts.text(1)).bind(4, attempts.text(2))
        .bind(5, attempts.integer(3)).bind(6, attempts.integer(4)).bind(7, attempts.integer(5))
        .bindBlob(8, attempts.blob(6)).bind(9, attempts.text(7)).run();
  }
  return true;
}

/// One pass over the source's completed trials: the check (`write` false) gathers conflicts;
/// the write (in the caller's transaction) copies the trials, counting them in `result`. On
/// PostgreSQL the write claims each pushed subject for `push_station` first.
std::vector<std::string> pushTrials(SqlConnection& from, SqlConnection& to, bool postgres, const std::string& push_station,
                                    bool write, StudyDatabase::PushResult& result) {
  std::vector<std::string> conflicts;
  std::string last_subject, claimed_subject;
  Statement trials(from, kCompletedTrials);
  while (trials.step()) {
    const std::string subject = trials.text(1);
    const std::int64_t sequence = trials.integer(2);
    // The same trial in the target: missing (-1), pending (0), completed the same (1) or
    // differently (2).
    std::int64_t target_id = 0;
    const auto targetState = [&]() { return targetTrialState(to, trials, subject, sequence, target_id); };
    // Counted in the pass that writes (the check's view may be stale by then).
    const auto settled = [&](int state) {
      if (state == -1) conflicts.push_back(fmt::format("subject {} trial {}: not in the target's plan", subject, sequence));
      if (state == 2) conflicts.push_back(fmt::format("subject {} trial {}: completed in both, differently", subject, sequence));
      if (state == 1 && write) ++result.already_there;
      return state != 0;
    };
    if (settled(targetState())) continue;
    if (!write) {
      if (!postgres) continue;
      noteRunningStation(to, subject, sequence, conflicts);
      continue;
    }
    if (postgres && subject != claimed_subject) {
      // The subject for the push: a station holding it refuses the push at once (the refused
      // claim keeps that station's lease row locked until this transaction ends); then the
      // trial is read again, as another push or a station may have completed it meanwhile.
      const SubjectClaim claim = detail::claimLeaseIn(to, push_station, subject, 3600.0);
      if (!claim.granted) {
        conflicts.push_back(fmt::format("subject {} trial {}: a station ({}) is running this subject now", subject,
                                        sequence, claim.holder));
        refusePush(from, to, conflicts);
      }
      claimed_subject = subject;
      if (settled(targetState())) continue;
    }
    // The trial as the source stored it, and its disturbed attempts.
    if (!copyTrial(from, to, trials, target_id)) {
      conflicts.push_back(fmt::format("subject {} trial {}: completed in the target during the push", subject, sequence));
      continue;
    }
    ++result.pushed;
    if (subject != last_subject) ++result.subjects;
    last_subject = subject;
  }
  return conflicts;
}

}  // namespace

StudyDatabase::PushResult StudyDatabase::pushFrom(const StudyDatabase& source) {
  SqlConnection& from = *source.db_;
  SqlConnection& to = *db_;
  HATTR_THROW_UNLESS(from.location() != to.location(), "study push: --from and --to are the same study ({})",
                     to.location());
  HATTR_THROW_UNLESS(onPostgres() || !runnerActive(), "study push: {} is being run by a runner now; push when the "
                     "run is over", to.location());
  if (const auto found = differences(from, to); !found.empty()) {
    std::string what;
    for (const auto& f : found) what += (what.empty() ? "" : "; ") + f;
    throw InputError(fmt::format("study push: {} and {} are not the same study: {}; expected both made by `hattr "
                                 "study init` from one study file", from.location(), to.location(), what));
  }

  // First every trial is checked, then all are written in one transaction (which checks again,
  // as a station may have started meanwhile): a refused push writes nothing. On PostgreSQL the
  // write takes each pushed subject's lease for the push (a lapsed station's too, as a station
  // would), so no station runs it meanwhile; they are given back at the end.
  PushResult result;
  const std::string push_station = onPostgres() ? detail::newStationId() : "";
  const auto push = [&](bool write) { return pushTrials(from, to, onPostgres(), push_station, write, result); };
  if (const auto conflicts = push(false); !conflicts.empty()) refusePush(from, to, conflicts);
  detail::Transaction t(to);
  if (const auto conflicts = push(true); !conflicts.empty()) refusePush(from, to, conflicts);  // rolled back
  if (onPostgres()) {
    Statement release(to, "DELETE FROM subject_leases WHERE station = ?");
    release.bind(1, push_station).run();
  }
  t.commit();
  return result;
}

}  // namespace hattr::session
