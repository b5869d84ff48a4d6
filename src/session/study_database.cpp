// The study store's queries, the same on both engines (sql_connection.hpp): creating and
// opening a study (each engine's own side is in study_sqlite.cpp and study_postgres.cpp),
// reading its definition, subjects and trials, and writing what a run does to them.

#include "hattr/session/study_database.hpp"

#include <unistd.h>

#include <algorithm>
#include <sstream>
#include <utility>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"
#include "hattr/io/profile_csv.hpp"
#include "sql_connection.hpp"
#include "study_database_internal.hpp"
#include "study_postgres.hpp"

namespace hattr::session {
namespace {

using nlohmann::json;

using detail::scalar;
using detail::SqlConnection;
using detail::SqlDialect;
using detail::Statement;
using detail::Transaction;

/// A trial's status as the trials table stores it ("pending" for anything unknown).
TrialStatus parseStatus(const std::string& text) {
  if (text == "running") return TrialStatus::kRunning;
  if (text == "completed") return TrialStatus::kCompleted;
  if (text == "interrupted") return TrialStatus::kInterrupted;
  return TrialStatus::kPending;
}

}  // namespace

std::string_view trialStatusName(TrialStatus status) {
  switch (status) {
    case TrialStatus::kPending: return "pending";
    case TrialStatus::kRunning: return "running";
    case TrialStatus::kCompleted: return "completed";
    case TrialStatus::kInterrupted: return "interrupted";
  }
  return "?";
}

// ---- Opening -------------------------------------------------------------------------------

bool isPostgresStudy(std::string_view location) { return detail::isPostgresLocation(location); }

StudyDatabase::StudyDatabase(std::filesystem::path file, std::unique_ptr<SqlConnection> db)
    : file_(std::move(file)), db_(std::move(db)) {}

StudyDatabase::StudyDatabase(StudyDatabase&& other) noexcept
    : file_(std::move(other.file_)), db_(std::move(other.db_)), lock_fd_(std::exchange(other.lock_fd_, -1)),
      options_(other.options_), station_(std::move(other.station_)), leases_(std::move(other.leases_)),
      study_(std::move(other.study_)) {}

StudyDatabase& StudyDatabase::operator=(StudyDatabase&& other) noexcept {
  std::swap(file_, other.file_);
  std::swap(db_, other.db_);
  std::swap(lock_fd_, other.lock_fd_);
  std::swap(options_, other.options_);
  std::swap(station_, other.station_);
  std::swap(leases_, other.leases_);
  std::swap(study_, other.study_);
  return *this;
}

StudyDatabase::~StudyDatabase() {
  // A station gives its subjects back on the way out (a killed one's leases lapse instead).
  if (leases_) {
    leases_.reset();
    try {
      Statement s(*db_, "DELETE FROM subject_leases WHERE station = ?");
      s.bind(1, station_).run();
    } catch (const std::exception&) {
    }
  }
  db_.reset();  // closed (SQLite: its WAL checked in) before the runner lock is given back
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

bool StudyDatabase::onPostgres() const noexcept { return db_ && db_->dialect() == SqlDialect::kPostgres; }

StudyDatabase StudyDatabase::create(const std::filesystem::path& file, const StudyDefinition& study,
                                    const std::function<void(StudyDatabase&)>& fill) {
  const bool postgres = isPostgresStudy(file.string());
  if (!postgres) {
    HATTR_THROW_UNLESS(!std::filesystem::exists(file), "{}: already exists; refusing to overwrite a study database",
                       file.string());
    const std::filesystem::path folder = file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path();
    HATTR_THROW_UNLESS(std::filesystem::is_directory(folder), "{}: no such folder (for the study database {})",
                       folder.string(), file.string());
  }
  // Read the experts first: a bad one leaves nothing half-made.
  std::map<std::string, std::string> expert_csv;
  for (const auto& [skill, path] : study.experts) {
    const auto named = study.named_expert_profiles.find(skill);
    HATTR_THROW_UNLESS(!study.named_experts.contains(skill) || named != study.named_expert_profiles.end(),
                       "experts.{}: \"{}\" names the simulated expert writing a glyph, recorded when a study is made "
                       "(`hattr study init`; in code, sim::recordNamedExperts before StudyDatabase::create)",
                       skill, study.named_experts.at(skill));
    std::ostringstream text;
    io::writeProfileCsv(named != study.named_expert_profiles.end() ? named->second : io::readProfileCsv(path), text);
    expert_csv[skill] = text.str();
  }
  return postgres ? createPostgres(file.string(), study, expert_csv, fill) : createSqlite(file, study, expert_csv, fill);
}

void StudyDatabase::writeNewStudy(const StudyDefinition& study, const std::map<std::string, std::string>& expert_csv) {
  HATTR_DEMAND(!study.groups.empty() && !study.schedule.empty(),
               "study \"{}\" has no groups or no schedule: a definition built in code needs applyPaperForm", study.name);
  SqlConnection& db = *db_;
  Statement insert(db, "INSERT INTO study (id, name, definition, created_utc) VALUES (1, ?, ?, ?)");
  insert.bind(1, study.name).bind(2, studyToJson(study).dump()).bind(3, utcNowIso8601()).run();
  for (const auto& [skill, csv] : expert_csv) {
    Statement e(db, "INSERT INTO experts (skill, profile_csv) VALUES (?, ?)");
    e.bind(1, skill).bind(2, csv).run();
  }
  const auto orders = modeOrders(study);
  for (std::size_t i = 0; i < study.subjects.size(); ++i) {
    const SubjectSpec& spec = study.subjects[i];
    json order = json::array();
    for (const auto m : orders[i]) order.push_back(std::string(guidance::modeName(m)));
    Statement s(db, "INSERT INTO subjects (id, position, mode_order, spec, group_name) VALUES (?, ?, ?, ?, ?)");
    s.bind(1, spec.id).bind(2, static_cast<int>(i)).bind(3, order.dump())
        .bind(4, json{{"participant", spec.participant}, {"seed", spec.seed}, {"options", spec.options}}.dump())
        .bind(5, spec.group)
        .run();
    for (const TrialPlan& p : planTrials(study, spec, orders[i])) {
      Statement tr(db,
                   "INSERT INTO trials (subject, sequence, mode, phase, trial_index, show_reference, guidance, skill, "
                   "schedule_session, day, block) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
      tr.bind(1, p.subject).bind(2, p.sequence).bind(3, guidance::modeName(p.mode)).bind(4, p.phase)
          .bind(5, p.index).bind(6, p.view.show_reference ? 1 : 0).bind(7, p.view.guidance ? 1 : 0).bind(8, p.skill)
          .bind(9, p.session).bind(10, p.day).bind(11, p.block).run();
    }
  }
  loadDefinition();
}

StudyDatabase StudyDatabase::open(const std::filesystem::path& file, OpenMode mode, const StoreOptions& options) {
  if (isPostgresStudy(file.string())) return openPostgres(file.string(), mode, options);
  return openSqlite(file, mode, options);
}

void StudyDatabase::loadDefinition() {
  Statement s(*db_, "SELECT definition FROM study WHERE id = 1");
  HATTR_THROW_UNLESS(s.step(), "{}: the study table is empty", file_.string());
  // Experts live in the database; the paths only record where they came from.
  study_ = parseStudy(s.text(0), file_.string() + ":study", "", false);
}

int StudyDatabase::schemaVersion() const {
  if (onPostgres()) return static_cast<int>(scalar(*db_, "SELECT schema_version FROM hattr_meta WHERE id = 1"));
  return static_cast<int>(scalar(*db_, "PRAGMA user_version"));
}

HapticProfile StudyDatabase::expert(const std::string& skill) const {
  Statement s(*db_, "SELECT profile_csv FROM experts WHERE skill = ?");
  s.bind(1, skill);
  HATTR_THROW_UNLESS(s.step(), "{}: no expert reference for skill \"{}\"", file_.string(), skill);
  std::istringstream in(s.text(0));
  return io::readProfileCsv(in, fmt::format("{}:experts/{}", file_.string(), skill));
}

std::vector<SubjectRecord> StudyDatabase::subjects() const {
  std::vector<SubjectRecord> out;
  Statement s(*db_, "SELECT id, position, mode_order, spec, group_name FROM subjects ORDER BY position");
  while (s.step()) {
    SubjectRecord r;
    r.id = s.text(0);
    r.position = static_cast<int>(s.integer(1));
    try {
      for (const auto& m : json::parse(s.text(2))) r.mode_order.push_back(guidance::parseMode(m.get<std::string>()));
      const json spec = json::parse(s.text(3));
      r.spec = {r.id, spec.at("participant").get<std::string>(), spec.at("seed").get<std::uint64_t>(), spec.at("options"),
                s.text(4)};
    } catch (const std::exception& e) {
      const auto* j = dynamic_cast<const json::exception*>(&e);
      throw InputError(fmt::format("{}: subject {} is damaged: {}", file_.string(), textExcerpt(r.id),
                                   j ? jsonLibraryMessage(*j) : std::string(e.what())));
    }
    out.push_back(std::move(r));
  }
  return out;
}

namespace {

/// A scheduled strategy's keys in a completed trial's stored metadata (TrialRecord::strategy_state).
/// Damaged metadata gives none: listing the trials never fails on it, and the schedule that
/// needs them names the trial (SubjectTrials).
std::map<std::string, std::string> strategyState(const std::string& metadata) {
  constexpr std::string_view kKeys[] = {"guidance_law", "guidance_gain", "tracking_rms_m"};
  std::map<std::string, std::string> state;
  if (metadata.find("tracking_rms_m") == std::string::npos) return state;  // not one (and no parse)
  const json parsed = json::parse(metadata, nullptr, false);
  if (!parsed.is_object() || !parsed.contains("extra") || !parsed["extra"].is_object()) return state;
  for (const std::string_view key : kKeys) {
    const auto it = parsed["extra"].find(key);
    if (it != parsed["extra"].end() && it->is_string()) state[std::string(key)] = it->get<std::string>();
  }
  return state;
}

}  // namespace

std::vector<TrialRecord> StudyDatabase::trials(const std::string& subject) const {
  std::vector<TrialRecord> out;
  Statement s(*db_,
              "SELECT t.id, t.subject, t.sequence, t.mode, t.phase, t.trial_index, t.show_reference, t.guidance, "
              "t.status, t.attempts, t.interruptions, t.started_utc, t.ended_utc, t.outcome, "
              "COALESCE(s.sample_count, 0), COALESCE(t.disturbed, ''), "
              "(SELECT COUNT(*) FROM disturbed_attempts d WHERE d.trial = t.id), COALESCE(t.skill, ''), "
              "t.schedule_session, t.day, t.block, u.group_name, COALESCE(t.metadata, '') "
              "FROM trials t LEFT JOIN samples s ON s.trial = t.id JOIN subjects u ON u.id = t.subject "
              "WHERE ? = '' OR t.subject = ? ORDER BY t.subject, t.sequence");
  s.bind(1, subject).bind(2, subject);
  while (s.step()) {
    TrialRecord r;
    r.id = s.integer(0);
    r.plan = {s.text(1), static_cast<int>(s.integer(2)), guidance::parseMode(s.text(3)), s.text(4),
              static_cast<int>(s.integer(5)), PhaseView{s.integer(6) != 0, s.integer(7) != 0}, s.text(17),
              s.text(21), static_cast<int>(s.integer(18)), static_cast<int>(s.integer(19)),
              static_cast<int>(s.integer(20))};
    if (r.plan.skill.empty()) r.plan.skill = study_.skill;
    r.status = parseStatus(s.text(8));
    r.attempts = static_cast<int>(s.integer(9));
    r.interruptions = static_cast<int>(s.integer(10));
    r.started_utc = s.text(11);
    r.ended_utc = s.text(12);
    r.outcome = s.text(13);
    r.sample_count = s.integer(14);
    r.disturbed = s.text(15);
    r.disturbed_attempts = static_cast<int>(s.integer(16));
    r.strategy_state = strategyState(s.text(22));
    out.push_back(std::move(r));
  }
  return out;
}

std::optional<TrialRecord> StudyDatabase::nextTrial(const std::string& subject) const {
  for (auto& t : trials(subject)) {
    if (t.status != TrialStatus::kCompleted) return t;
  }
  return std::nullopt;
}

HapticProfile StudyDatabase::trialProfile(std::int64_t trial_id) const {
  Statement s(*db_,
              "SELECT s.raw_pressure, s.raw_tilt, s.sample_count, s.data, t.metadata, t.subject, t.sequence, s.encoding "
              "FROM samples s JOIN trials t ON t.id = s.trial WHERE s.trial = ?");
  s.bind(1, trial_id);
  if (!s.step()) {
    // A completed trial without samples was run in a scratch study (completeTrial otherwise
    // stores them in the same transaction).
    Statement status(*db_, "SELECT status FROM trials WHERE id = ?");
    status.bind(1, trial_id);
    const bool completed = status.step() && status.text(0) == "completed";
    throw InputError(fmt::format("{}: trial {} has no recorded samples{}", file_.string(), trial_id,
                                 completed ? " (it was run in a scratch study, which keeps none)" : ""));
  }
  // What was stored is checked as it is read back: a damaged trial is named, never half-read.
  try {
    const RawChannels raw{s.integer(0) != 0, s.integer(1) != 0};
    HapticProfile profile(parseProfileMetadataJson(s.text(4), "metadata"), raw);
    const auto samples =
        decodeTrialSamples(s.blob(3), s.text(7), raw, static_cast<std::size_t>(std::max<std::int64_t>(s.integer(2), 0)));
    profile.reserve(samples.size());
    for (const Sample& sample : samples) profile.append(sample);
    return profile;
  } catch (const std::exception& e) {
    throw InputError(fmt::format("{}: trial {} (subject {}, sequence {}) is damaged: {}", file_.string(), trial_id,
                                 textExcerpt(s.text(5)), s.integer(6), e.what()));
  }
}

// ---- Writing ---------------------------------------------------------------------------------

std::int64_t StudyDatabase::beginSession(const std::string& subject) {
  Statement s(*db_, "INSERT INTO sessions (subject, started_utc, pid, host) VALUES (?, ?, ?, ?) RETURNING id");
  s.bind(1, subject).bind(2, utcNowIso8601()).bind(3, static_cast<std::int64_t>(::getpid())).bind(4, detail::hostName());
  HATTR_DEMAND(s.step(), "a new session has no id");
  return s.integer(0);
}

void StudyDatabase::endSession(std::int64_t session_id) {
  Statement s(*db_, "UPDATE sessions SET ended_utc = ? WHERE id = ?");
  s.bind(1, utcNowIso8601()).bind(2, session_id).run();
}

bool StudyDatabase::runnerActive() const {
  if (onPostgres()) return scalar(*db_, "SELECT COUNT(*) FROM subject_leases WHERE expires_at > clock_timestamp()") > 0;
  return lock_fd_ >= 0 || detail::runnerLockHeld(file_);
}

void StudyDatabase::holdLease(std::int64_t trial_id) {
  if (!leases_) return;  // SQLite, or not a station (an import, a push: they check for stations themselves)
  // The station's lease row, locked until the write's transaction ends: a takeover (which
  // updates that row) waits for the write, and a write waits for a takeover and then finds
  // the row another station's.
  Statement s(*db_, "SELECT 1 FROM subject_leases WHERE station = ? AND subject = (SELECT subject FROM trials "
                    "WHERE id = ?) FOR SHARE");
  s.bind(1, station_).bind(2, trial_id);
  if (!s.step()) refuseUnwritable(0, trial_id, "written");
}

void StudyDatabase::markRunning(std::int64_t trial_id, std::int64_t session_id) {
  std::optional<Transaction> t;
  if (leases_) t.emplace(*db_);
  holdLease(trial_id);
  Statement s(*db_, "UPDATE trials SET status = 'running', attempts = attempts + 1, session = ?, started_utc = ? "
                    "WHERE id = ? AND status != 'completed'");
  s.bind(1, session_id).bind(2, utcNowIso8601()).bind(3, trial_id).run();
  refuseUnwritable(s.changes(), trial_id, "run again");
  if (t) t->commit();
}

void StudyDatabase::refuseUnwritable(std::int64_t changed, std::int64_t trial_id, std::string_view what) const {
  if (changed == 1) return;
  if (leases_) {
    // The subject's lease is not this station's: another station took the subject over.
    Statement s(*db_, "SELECT t.status, t.subject, l.host, l.pid, l.station = ? FROM trials t "
                      "LEFT JOIN subject_leases l ON l.subject = t.subject WHERE t.id = ?");
    s.bind(1, station_).bind(2, trial_id);
    if (s.step() && (s.isNull(4) || s.integer(4) == 0)) {
      throw SubjectTakenOver(fmt::format("study database {}: trial {}: subject {} is no longer this station's (its lease "
                              "lapsed: not renewed for {} s{}); this station stores nothing more of it",
                              file_.string(), trial_id, s.text(1), options_.lease_timeout_s,
                              s.isNull(2) ? "" : fmt::format(", and process {} on {} holds it now", s.integer(3), s.text(2))));
    }
  }
  throw Error(fmt::format("study database {}: trial {} is completed or missing; a completed trial is never {}",
                          file_.string(), trial_id, what));
}

void StudyDatabase::completeTrial(std::int64_t trial_id, const HapticProfile& profile, const std::string& outcome,
                                  const std::string& disturbed) {
  const std::string data = options_.scratch ? std::string() : encodeTrialSamples(profile, study_.resolution);
  Transaction t(*db_);
  holdLease(trial_id);
  Statement trial(*db_, "UPDATE trials SET status = 'completed', ended_utc = ?, outcome = ?, metadata = ?, disturbed = ? "
                        "WHERE id = ? AND status != 'completed'");
  trial.bind(1, utcNowIso8601()).bind(2, outcome).bind(3, profileMetadataJson(profile.metadata()));
  if (disturbed.empty()) {
    trial.bindNull(4);
  } else {
    trial.bind(4, disturbed);
  }
  trial.bind(5, trial_id).run();
  refuseUnwritable(trial.changes(), trial_id, "replaced");
  if (options_.scratch) {  // the row only: the caller scored the samples as the trial ended
    t.commit();
    return;
  }
  Statement samples(*db_,
                    "INSERT INTO samples (trial, raw_pressure, raw_tilt, sample_count, data, encoding) "
                    "VALUES (?, ?, ?, ?, ?, ?) ON CONFLICT (trial) DO UPDATE SET raw_pressure = excluded.raw_pressure, "
                    "raw_tilt = excluded.raw_tilt, sample_count = excluded.sample_count, data = excluded.data, "
                    "encoding = excluded.encoding");
  samples.bind(1, trial_id).bind(2, profile.rawChannels().pressure ? 1 : 0).bind(3, profile.rawChannels().tilt ? 1 : 0)
      .bind(4, static_cast<std::int64_t>(profile.size())).bindBlob(5, data).bind(6, std::string(kCompactSamples)).run();
  t.commit();
}

// The attempt is kept and the trial is pending again, at once: a process that dies before the
// repeat begins left no attempt running, so none is counted as an interruption besides.
void StudyDatabase::keepDisturbedAttempt(std::int64_t trial_id, const HapticProfile& profile, const std::string& reason) {
  Transaction t(*db_);
  holdLease(trial_id);
  Statement s(*db_,
              "INSERT INTO disturbed_attempts (trial, reason, ended_utc, metadata, raw_pressure, raw_tilt, sample_count, "
              "data, encoding) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)");
  s.bind(1, trial_id).bind(2, reason).bind(3, utcNowIso8601()).bind(4, profileMetadataJson(profile.metadata()))
      .bind(5, profile.rawChannels().pressure ? 1 : 0).bind(6, profile.rawChannels().tilt ? 1 : 0)
      .bind(7, static_cast<std::int64_t>(profile.size())).bindBlob(8, encodeTrialSamples(profile, study_.resolution))
      .bind(9, std::string(kCompactSamples)).run();
  Statement pending(*db_, "UPDATE trials SET status = 'pending' WHERE id = ? AND status = 'running'");
  pending.bind(1, trial_id).run();
  t.commit();
}

void StudyDatabase::failTrial(std::int64_t trial_id, const std::string& reason) {
  std::optional<Transaction> t;
  if (leases_) t.emplace(*db_);
  try {
    holdLease(trial_id);
  } catch (const SubjectTakenOver&) {
    return;  // the station that took the subject over has marked the trial interrupted
  }
  Statement s(*db_, "UPDATE trials SET status = 'interrupted', interruptions = interruptions + 1, ended_utc = ?, "
                    "outcome = ? WHERE id = ? AND status = 'running'");
  s.bind(1, utcNowIso8601()).bind(2, "failed: " + reason).bind(3, trial_id).run();
  if (t) t->commit();
}

void StudyDatabase::putResult(const std::string& key, const std::string& value) {
  Statement s(*db_, "INSERT INTO results (key, value, updated_utc) VALUES (?, ?, ?) ON CONFLICT (key) DO UPDATE SET "
                    "value = excluded.value, updated_utc = excluded.updated_utc");
  s.bind(1, key).bind(2, value).bind(3, utcNowIso8601()).run();
}

std::optional<std::string> StudyDatabase::result(const std::string& key) const {
  Statement s(*db_, "SELECT value FROM results WHERE key = ?");
  s.bind(1, key);
  if (!s.step()) return std::nullopt;
  return s.text(0);
}

// ---- Subjects and stations -------------------------------------------------------------------

SubjectClaim StudyDatabase::claimSubject(const std::string& subject) {
  HATTR_DEMAND(lock_fd_ >= 0 || leases_ != nullptr, "a subject claimed by a study not opened as its runner");
  if (!onPostgres()) return {true, ""};
  return detail::claimLease(*db_, station_, subject, options_.lease_timeout_s);
}

void StudyDatabase::releaseSubject(const std::string& subject) {
  if (!leases_) return;  // SQLite: the runner lock holds the whole study
  Statement s(*db_, "DELETE FROM subject_leases WHERE subject = ? AND station = ?");
  s.bind(1, subject).bind(2, station_).run();
}

double StudyDatabase::claimRetryInterval_s() const noexcept {
  // A quarter of the lease, so that a dead station's subject is taken over soon after it lapses,
  // and at most a second, so that a subject given back or the study's end is noticed soon
  // whatever the lease (each round is one claim query a waiting subject).
  return std::min(options_.lease_timeout_s / 4.0, kMaxClaimRetry_s);
}

std::string profileMetadataJson(const ProfileMetadata& m) {
  const json j{{"subject", m.subject}, {"skill", m.skill},   {"device", m.device},
               {"source", m.source},   {"created_utc", m.created_utc}, {"rate_hz", m.nominal_rate_hz},
               {"extra", m.extra}};
  return j.dump();
}

ProfileMetadata parseProfileMetadataJson(std::string_view text, std::string_view where) {
  try {
    const json meta = json::parse(text);
    return {meta.at("subject"), meta.at("skill"), meta.at("device"), meta.at("source"), meta.at("created_utc"),
            meta.at("rate_hz").get<double>(), meta.at("extra").get<std::map<std::string, std::string>>()};
  } catch (const json::exception& e) {
    throw InputError(fmt::format("{}: {}", where, jsonLibraryMessage(e)));
  }
}

}  // namespace hattr::session
