#pragma once
/// The study database: one SQLite file per study holding the definition, the expert
/// references, the subjects with their mode orders, the sessions, every trial's plan and
/// status, and the full-rate profile of every completed trial. Crash-safe:
/// - WAL journal, synchronous=FULL: a committed trial survives a crash or power loss;
/// - each trial is committed in its own transaction the moment it ends, profile and status
///   together: never half-written;
/// - a trial that was running when its process died is marked interrupted on the next run
///   and run again; nothing completed is lost;
/// - one runner at a time: a second process gets a clear error (an exclusive lock);
/// - a file that is not a study database, or from a newer schema, is refused.
/// Schema and migrations: docs/studies.md.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/session/study.hpp"

struct sqlite3;

namespace hattr::session {

/// The schema this build writes; it reads every version from 1 up to this one.
inline constexpr int kStudySchemaVersion = 4;
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
};

struct SubjectRecord {
  std::string id;
  int position = 0;
  std::vector<guidance::TrainingMode> mode_order;
  SubjectSpec spec;
};

enum class OpenMode { kReadOnly, kReadWrite, kRunner };

class StudyDatabase {
 public:
  /// Creates a new study file from a definition (refuses to overwrite an existing file):
  /// stores the definition, copies the expert profiles in, assigns mode orders and plans
  /// every trial; then `fill` (if any) adds to it (an import's trials). All or nothing: the
  /// file is built under a hidden name beside `file` and linked into place only when
  /// complete, so a failure (of `fill` too), a kill or a full disk leaves no `file` behind.
  /// Returns it opened kReadWrite. Throws InputError for an existing file or bad experts.
  static StudyDatabase create(const std::filesystem::path& file, const StudyDefinition& study,
                              const std::function<void(StudyDatabase&)>& fill = {});

  /// Opens a study file. kRunner takes the exclusive runner lock (another runner: InputError
  /// naming the file and the holder) and marks trials left running as interrupted. Refuses
  /// a file that is not a hattr study or has a newer schema (InputError); migrates an older
  /// one (kReadWrite, kRunner).
  static StudyDatabase open(const std::filesystem::path& file, OpenMode mode);

  StudyDatabase(StudyDatabase&&) noexcept;
  StudyDatabase& operator=(StudyDatabase&&) noexcept;
  ~StudyDatabase();

  [[nodiscard]] const StudyDefinition& study() const noexcept { return study_; }
  [[nodiscard]] const std::filesystem::path& file() const noexcept { return file_; }
  [[nodiscard]] int schemaVersion() const;
  [[nodiscard]] HapticProfile expert(const std::string& skill) const;
  [[nodiscard]] std::vector<SubjectRecord> subjects() const;
  [[nodiscard]] std::vector<TrialRecord> trials(const std::string& subject = "") const;
  /// The first trial of the subject that is not completed, if any.
  [[nodiscard]] std::optional<TrialRecord> nextTrial(const std::string& subject) const;
  /// The recorded profile of a completed trial, exactly as stored.
  [[nodiscard]] HapticProfile trialProfile(std::int64_t trial_id) const;

  /// Whether a runner holds the study now (this one, or another process): then a trial marked
  /// running is being run, not interrupted.
  [[nodiscard]] bool runnerActive() const;

  /// Starts a session (a run of the protocol by this process); returns its id.
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

  /// Key/value results of analyses (the analysis issue stores its tables here).
  void putResult(const std::string& key, const std::string& value);
  [[nodiscard]] std::optional<std::string> result(const std::string& key) const;

 private:
  /// Throws hattr::Error unless `changed` is 1: the trial was completed (or is not there).
  void refuseCompleted(std::int64_t changed, std::int64_t trial_id, std::string_view what) const;
  /// create(): the schema, the definition, the experts, the subjects and their trial plans.
  void writeNewStudy(const StudyDefinition& study, const std::map<std::string, std::string>& expert_csv);
  StudyDatabase(std::filesystem::path file, sqlite3* db, int lock_fd);
  void loadDefinition();

  std::filesystem::path file_;
  sqlite3* db_ = nullptr;
  int lock_fd_ = -1;
  StudyDefinition study_;
};

/// The samples tables' encodings: "hsc1", io/sample_codec's compact blocks (since schema 4),
/// and "f64-rows", schema 3's little-endian doubles, one row per sample (read, and rewritten as
/// hsc1 by the migration to schema 4).
inline constexpr std::string_view kCompactSamples = "hsc1";
inline constexpr std::string_view kRowSamples = "f64-rows";

/// A profile's samples as the samples table stores them: io::encodeSamples on the profile's
/// stored channels, lossless or at `resolution`.
std::string encodeTrialSamples(const HapticProfile& profile, const io::ChannelResolution& resolution = {});
/// A stored block back into samples, from either encoding; throws InputError for a damaged one.
std::vector<Sample> decodeTrialSamples(std::string_view bytes, std::string_view encoding, const RawChannels& raw,
                                       std::size_t count);

}  // namespace hattr::session
