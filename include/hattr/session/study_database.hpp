#pragma once
/// The study database: one SQLite file per study (one station), or one PostgreSQL database
/// per study (many stations), holding the definition, the expert references, the subjects
/// with their mode orders, the sessions, every trial's plan and status, and the full-rate
/// profile of every completed trial. Crash-safe:
/// - WAL journal, synchronous=FULL: a committed trial survives a crash or power loss;
/// - each trial is committed in its own transaction the moment it ends, profile and status
///   together: never half-written;
/// - a trial that was running when its process died is marked interrupted on the next run
///   and run again; nothing completed is lost;
/// - SQLite: one runner at a time: a second process gets a clear error (an exclusive lock);
/// - PostgreSQL: many runners (stations), each subject run by one at a time under a lease that
///   the station renews; a station that stops renewing loses its subjects after the lease
///   timeout, and its running trial becomes interrupted, as a crash does on SQLite;
/// - a file that is not a study database, or from a newer schema, is refused.
/// Schema and migrations: docs/studies.md; stations: docs/study-store.md.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hattr/core/error.hpp"
#include "hattr/core/haptic_profile.hpp"
#include "hattr/session/study.hpp"

namespace hattr::session {

namespace detail {
class SqlConnection;
class Statement;
class LeaseKeeper;
}  // namespace detail

/// The schema this build writes; it reads every version from 1 up to this one.
inline constexpr int kStudySchemaVersion = 5;
/// SQLite application_id of hattr study files ("hatt").
inline constexpr std::int32_t kStudyApplicationId = 0x68617474;

enum class TrialStatus { kPending, kRunning, kCompleted, kInterrupted };
std::string_view trialStatusName(TrialStatus status);

/// One row of the trials table.
struct TrialRecord {
  std::int64_t id = 0;
  TrialPlan plan;
  TrialStatus status = TrialStatus::kPending;
  int attempts = 0;
  int interruptions = 0;
  std::string started_utc;
  std::string ended_utc;
  std::string outcome;
  std::int64_t sample_count = 0;
  std::string disturbed;        ///< how the loop disturbed the kept attempt ("" when clean)
  int disturbed_attempts = 0;   ///< disturbed attempts kept and run again (policy "repeat")
  /// A completed trial of a scheduled strategy: what its schedule chose and measured, from its
  /// stored metadata (guidance_law, guidance_gain, tracking_rms_m); empty for any other.
  std::map<std::string, std::string> strategy_state;
};

struct SubjectRecord {
  std::string id;
  int position = 0;
  std::vector<guidance::TrainingMode> mode_order;
  SubjectSpec spec;
};

enum class OpenMode { kReadOnly, kReadWrite, kRunner };

/// How a study is held open.
struct StoreOptions {
  /// PostgreSQL (SQLite has one runner: no leases): a subject's lease lapses this long after
  /// its station's last renewal (renewed every third of it); then another station may take
  /// the subject over.
  double lease_timeout_s = 30.0;
  /// A scratch study, SQLite only (a power analysis's replicate, scored as its trials end and
  /// removed once analyzed): a completed trial's row and metadata are stored but not its
  /// samples (trialProfile refuses the trial; a disturbed attempt kept for the record is stored
  /// whole), and commits are not synced to disk. Never for data that matters.
  bool scratch = false;
};

/// A station's write refused because another station took the subject over (PostgreSQL: this
/// station's lease lapsed); nothing of the write was stored. The runner moves on to other subjects.
class SubjectTakenOver : public Error {
 public:
  using Error::Error;
};

/// Whether this process may run a subject now, and if not, who does.
struct SubjectClaim {
  bool granted = false;
  std::string holder;  ///< "process 123 on host-a, lease for 12 s more" when not granted
};

/// Whether `location` names a PostgreSQL study (postgresql://... or postgres://...), not a file.
bool isPostgresStudy(std::string_view location);

class StudyDatabase {
 public:
  /// `file` is a study file, or a PostgreSQL database's address (postgresql://...; no
  /// password in it: libpq's password file, service file or environment supply it).
  ///
  /// Creates a new study file from a definition (refuses to overwrite an existing file):
  /// stores the definition, copies the expert profiles in, assigns mode orders and plans
  /// every trial; then `fill` (if any) adds to it (an import's trials). All or nothing: the
  /// file is built under a hidden name beside `file` and linked into place only when
  /// complete, so a failure (of `fill` too), a kill or a full disk leaves no `file` behind.
  /// Returns it opened kReadWrite. Throws InputError for an existing file or bad experts.
  /// On PostgreSQL the database must hold no study; a failed create leaves it empty.
  static StudyDatabase create(const std::filesystem::path& file, const StudyDefinition& study,
                              const std::function<void(StudyDatabase&)>& fill = {});

  /// Opens a study file. kRunner takes the exclusive runner lock (another runner: InputError
  /// naming the file and the holder) and marks trials left running as interrupted. Refuses
  /// a file that is not a hattr study or has a newer schema (InputError); migrates an older
  /// one (kReadWrite, kRunner). On PostgreSQL, kRunner makes this process a station: it runs
  /// the subjects it claims (claimSubject), and a thread renews its leases.
  static StudyDatabase open(const std::filesystem::path& file, OpenMode mode, const StoreOptions& options = {});

  StudyDatabase(StudyDatabase&&) noexcept;
  StudyDatabase& operator=(StudyDatabase&&) noexcept;
  ~StudyDatabase();

  [[nodiscard]] const StudyDefinition& study() const noexcept { return study_; }
  /// A scratch study (StoreOptions::scratch): its trials are scored as they end and removed.
  [[nodiscard]] bool scratch() const noexcept { return options_.scratch; }
  /// The study file, or the PostgreSQL address (for messages).
  [[nodiscard]] const std::filesystem::path& file() const noexcept { return file_; }
  [[nodiscard]] bool onPostgres() const noexcept;
  [[nodiscard]] int schemaVersion() const;
  [[nodiscard]] HapticProfile expert(const std::string& skill) const;
  [[nodiscard]] std::vector<SubjectRecord> subjects() const;
  [[nodiscard]] std::vector<TrialRecord> trials(const std::string& subject = "") const;
  /// The first trial of the subject that is not completed, if any.
  [[nodiscard]] std::optional<TrialRecord> nextTrial(const std::string& subject) const;
  /// The recorded profile of a completed trial, exactly as stored.
  [[nodiscard]] HapticProfile trialProfile(std::int64_t trial_id) const;

  /// Whether a runner holds the study now (this one, or another process; on PostgreSQL, a
  /// station holds a lease): then a trial marked running is being run, not interrupted.
  [[nodiscard]] bool runnerActive() const;

  /// Takes a subject for this runner (kRunner). SQLite: always granted (the runner lock holds
  /// the whole study). PostgreSQL: granted when no other station's lease on it is live; a
  /// lapsed station's running trials become interrupted and its sessions end.
  SubjectClaim claimSubject(const std::string& subject);
  /// Gives the subject back (PostgreSQL: drops the lease); quiet when not held.
  void releaseSubject(const std::string& subject);
  /// How long a station waits before asking again for subjects other stations hold: a quarter
  /// of the lease timeout, at most kMaxClaimRetry_s [s].
  [[nodiscard]] double claimRetryInterval_s() const noexcept;
  static constexpr double kMaxClaimRetry_s = 1.0;

  /// Starts a session (a run of the protocol by this process); returns its id.
  /// Writing a trial (markRunning to failTrial) on PostgreSQL needs this station's lease on
  /// its subject: a station whose subject was taken over gets SubjectTakenOver and stores nothing.
  std::int64_t beginSession(const std::string& subject);
  void endSession(std::int64_t session_id);
  /// Marks a trial running (its own transaction). A completed trial is never run again or
  /// replaced: markRunning and completeTrial throw hattr::Error for one.
  void markRunning(std::int64_t trial_id, std::int64_t session_id);
  /// Stores a finished trial's profile and marks it completed, in one transaction;
  /// `disturbed` says how the loop disturbed it ("" when clean).
  void completeTrial(std::int64_t trial_id, const HapticProfile& profile, const std::string& outcome,
                     const std::string& disturbed = "");
  /// Keeps a disturbed attempt of a running trial (samples and metadata) before it is run again.
  void keepDisturbedAttempt(std::int64_t trial_id, const HapticProfile& profile, const std::string& reason);
  /// A running trial that failed (device fault, lost link): interrupted, outcome "failed:
  /// <reason>"; nothing of it is kept, and the next run repeats it. Completed trials are untouched.
  void failTrial(std::int64_t trial_id, const std::string& reason);

  /// What a push did: trials copied, trials already there (the same to the byte).
  struct PushResult {
    int pushed = 0;
    int already_there = 0;
    int subjects = 0;  ///< subjects with trials pushed
  };
  /// Copies every completed trial of `source` (the same study, run elsewhere: a station's
  /// SQLite file run offline) into this study: samples as stored, metadata, attempts and
  /// disturbed attempts. Idempotent: a trial already here the same to the byte is skipped.
  /// Refuses, writing nothing, with an InputError listing them: another study (definition,
  /// experts or plan differ), a trial completed here differently, or a subject with trials to
  /// push that a station is running now. All of it in one transaction.
  PushResult pushFrom(const StudyDatabase& source);

  /// Key/value results of analyses (the analysis issue stores its tables here).
  void putResult(const std::string& key, const std::string& value);
  [[nodiscard]] std::optional<std::string> result(const std::string& key) const;

 private:
  /// Throws hattr::Error unless `changed` is 1: the trial was completed, is not there, or (on
  /// PostgreSQL) its subject is no longer this station's.
  void refuseUnwritable(std::int64_t changed, std::int64_t trial_id, std::string_view what) const;
  /// A station's write of a trial (PostgreSQL, in the write's transaction): locks this
  /// station's lease on the trial's subject, or throws SubjectTakenOver. Nothing otherwise.
  void holdLease(std::int64_t trial_id);
  /// create(): the definition, the experts, the subjects and their trial plans.
  void writeNewStudy(const StudyDefinition& study, const std::map<std::string, std::string>& expert_csv);
  static StudyDatabase createSqlite(const std::filesystem::path& file, const StudyDefinition& study,
                                    const std::map<std::string, std::string>& expert_csv,
                                    const std::function<void(StudyDatabase&)>& fill);
  static StudyDatabase createPostgres(const std::string& location, const StudyDefinition& study,
                                      const std::map<std::string, std::string>& expert_csv,
                                      const std::function<void(StudyDatabase&)>& fill);
  static StudyDatabase openSqlite(const std::filesystem::path& file, OpenMode mode, const StoreOptions& options);
  static StudyDatabase openPostgres(const std::string& location, OpenMode mode, const StoreOptions& options);
  StudyDatabase(std::filesystem::path file, std::unique_ptr<detail::SqlConnection> db);
  void loadDefinition();

  std::filesystem::path file_;
  std::unique_ptr<detail::SqlConnection> db_;
  int lock_fd_ = -1;                              ///< SQLite: the runner lock
  StoreOptions options_;
  std::string station_;                           ///< PostgreSQL runner: this station's id
  std::unique_ptr<detail::LeaseKeeper> leases_;   ///< PostgreSQL runner: renews the leases
  StudyDefinition study_;
};

/// The samples tables' encodings: "hsc2" (io::kSampleEncoding), io/sample_codec's compact
/// blocks as this build writes them; "hsc1", their first revision (schema 4's blocks before
/// hsc2), still read; and "f64-rows", schema 3's little-endian doubles, one row per sample (read,
/// and rewritten compactly by the migration to schema 4).
inline constexpr std::string_view kCompactSamples = io::kSampleEncoding;
inline constexpr std::string_view kCompactSamplesV1 = io::kSampleEncodingV1;
inline constexpr std::string_view kRowSamples = "f64-rows";

/// A profile's samples as the samples table stores them: io::encodeSamples on the profile's
/// stored channels, lossless or at `resolution`.
std::string encodeTrialSamples(const HapticProfile& profile, const io::ChannelResolution& resolution = {});
/// A stored block back into samples, from either encoding; throws InputError for a damaged one.
std::vector<Sample> decodeTrialSamples(std::string_view bytes, std::string_view encoding, const RawChannels& raw,
                                       std::size_t count);
/// A profile's metadata as the stores keep it: a JSON object (subject, skill, device, source,
/// created_utc, rate_hz, extra), keys sorted.
std::string profileMetadataJson(const ProfileMetadata& metadata);
/// profileMetadataJson's text back; throws InputError naming `where` for text that is not one.
ProfileMetadata parseProfileMetadataJson(std::string_view text, std::string_view where);

}  // namespace hattr::session
