// The study store's schema on SQLite and its migrations, version by version (docs/studies.md),
// and the migration to designs that both stores run. PostgreSQL's own schema, which starts at
// version 4, is in study_postgres.cpp.

#include <algorithm>
#include <bit>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"
#include "hattr/session/study_database.hpp"
#include "study_database_internal.hpp"

namespace hattr::session {
namespace {

using nlohmann::json;

using detail::scalar;
using detail::SqlConnection;
using detail::Statement;
using detail::Transaction;

/// Version 1, as first released: kept verbatim so migrations start from it.
constexpr std::string_view kSchemaV1 = R"(
CREATE TABLE study (id INTEGER PRIMARY KEY CHECK (id = 1), name TEXT NOT NULL, definition TEXT NOT NULL,
                    created_utc TEXT NOT NULL);
CREATE TABLE experts (skill TEXT PRIMARY KEY, profile_csv TEXT NOT NULL);
CREATE TABLE subjects (id TEXT PRIMARY KEY, position INTEGER NOT NULL, mode_order TEXT NOT NULL, spec TEXT NOT NULL);
CREATE TABLE sessions (id INTEGER PRIMARY KEY, subject TEXT NOT NULL REFERENCES subjects(id), started_utc TEXT NOT NULL,
                       ended_utc TEXT, pid INTEGER NOT NULL, host TEXT NOT NULL);
CREATE TABLE trials (id INTEGER PRIMARY KEY, subject TEXT NOT NULL REFERENCES subjects(id), sequence INTEGER NOT NULL,
                     mode TEXT NOT NULL, phase TEXT NOT NULL, trial_index INTEGER NOT NULL,
                     show_reference INTEGER NOT NULL, guidance INTEGER NOT NULL,
                     status TEXT NOT NULL DEFAULT 'pending', attempts INTEGER NOT NULL DEFAULT 0,
                     session INTEGER REFERENCES sessions(id), started_utc TEXT, ended_utc TEXT, outcome TEXT,
                     metadata TEXT, UNIQUE (subject, sequence));
CREATE TABLE samples (trial INTEGER PRIMARY KEY REFERENCES trials(id), raw_pressure INTEGER NOT NULL,
                      raw_tilt INTEGER NOT NULL, sample_count INTEGER NOT NULL, data BLOB NOT NULL);
)";

/// Migration 1 -> 2: interrupted attempts are counted per trial, and analyses get a table.
constexpr std::string_view kMigrationV1ToV2 = R"(
ALTER TABLE trials ADD COLUMN interruptions INTEGER NOT NULL DEFAULT 0;
CREATE TABLE results (key TEXT PRIMARY KEY, value TEXT NOT NULL, updated_utc TEXT NOT NULL);
)";

/// Migration 2 -> 3: a trial the loop disturbed says how; a disturbed attempt that was run
/// again is kept whole.
constexpr std::string_view kMigrationV2ToV3 = R"(
ALTER TABLE trials ADD COLUMN disturbed TEXT;
CREATE TABLE disturbed_attempts (id INTEGER PRIMARY KEY, trial INTEGER NOT NULL REFERENCES trials(id),
                                 reason TEXT NOT NULL, ended_utc TEXT NOT NULL, metadata TEXT NOT NULL,
                                 raw_pressure INTEGER NOT NULL, raw_tilt INTEGER NOT NULL,
                                 sample_count INTEGER NOT NULL, data BLOB NOT NULL);
)";

/// Migration 3 -> 4: each block of samples says its encoding; those of schema 3 (rows of
/// doubles) are rewritten in the compact encoding by compactStoredSamples, losslessly.
constexpr std::string_view kMigrationV3ToV4 = R"(
ALTER TABLE samples ADD COLUMN encoding TEXT NOT NULL DEFAULT 'f64-rows';
ALTER TABLE disturbed_attempts ADD COLUMN encoding TEXT NOT NULL DEFAULT 'f64-rows';
)";

/// Migration 4 -> 5: each trial says its place in the design (skill, session of the schedule,
/// its day, block) and each subject its group; filled in for the studies before designs by
/// fillDesignColumns.
constexpr std::string_view kMigrationV4ToV5 = R"(
ALTER TABLE trials ADD COLUMN skill TEXT;
ALTER TABLE trials ADD COLUMN schedule_session INTEGER NOT NULL DEFAULT 0;
ALTER TABLE trials ADD COLUMN day INTEGER NOT NULL DEFAULT 0;
ALTER TABLE trials ADD COLUMN block INTEGER NOT NULL DEFAULT 0;
ALTER TABLE subjects ADD COLUMN group_name TEXT NOT NULL DEFAULT 'all';
)";

constexpr std::string_view kMigrations[] = {kMigrationV1ToV2, kMigrationV2ToV3, kMigrationV3ToV4};

/// Every block of samples still in schema 3's rows, rewritten in the compact encoding
/// (lossless), in the caller's transaction; each is decoded again and compared bit for bit
/// with the rows before it replaces them. A block that does not decode is left as it is.
void compactTable(SqlConnection& db, std::string_view table, std::string_view key) {
  // The rows to rewrite first (a cursor must not walk rows its own connection updates).
  std::vector<std::int64_t> ids;
  {
    Statement list(db, fmt::format("SELECT {} FROM {} WHERE encoding = '{}'", key, table, kRowSamples));
    while (list.step()) ids.push_back(list.integer(0));
  }
  for (const std::int64_t id : ids) {
    Statement rows(db, fmt::format("SELECT raw_pressure, raw_tilt, sample_count, data FROM {} WHERE {} = ?", table, key));
    rows.bind(1, id);
    HATTR_DEMAND(rows.step(), "a row listed for the migration is gone");
    const RawChannels raw{rows.integer(0) != 0, rows.integer(1) != 0};
    const auto count = static_cast<std::size_t>(std::max<std::int64_t>(rows.integer(2), 0));
    const auto channels = detail::storedChannels(raw);
    // A damaged block stays as it was: it is reported when it is read, as before, and the
    // rest of the study migrates.
    std::vector<Sample> samples;
    try {
      samples = detail::decodeRowSamples(rows.blob(3), raw, count);
    } catch (const InputError&) {
      continue;
    }
    const std::string compact = io::encodeSamples(samples, channels);
    const auto back = io::decodeSamples(compact, channels, count);
    for (std::size_t i = 0; i < count; ++i) {
      for (const Channel c : channels) {
        HATTR_DEMAND(std::bit_cast<std::uint64_t>(channelValue(back[i], c)) ==
                         std::bit_cast<std::uint64_t>(channelValue(samples[i], c)),
                     "the compact encoding did not give back every sample of a stored trial");
      }
    }
    Statement update(db, fmt::format("UPDATE {} SET data = ?, encoding = ? WHERE {} = ?", table, key));
    update.bindBlob(1, compact).bind(2, std::string(kCompactSamples)).bind(3, id).run();
  }
}

/// Migration 3 -> 4's rewrite: both tables that hold blocks of samples.
void compactStoredSamples(SqlConnection& db) {
  compactTable(db, "samples", "trial");
  compactTable(db, "disturbed_attempts", "id");
}

}  // namespace

/// An SQLite study brought from `from_version` up to this build's schema, a step at a time.
void detail::migrateSqlite(SqlConnection& db, int from_version) {
  for (int v = from_version; v < kStudySchemaVersion; ++v) {
    Transaction t(db);
    // Another writer may have taken this step while we waited for the lock.
    if (scalar(db, "PRAGMA user_version") > v) continue;
    if (v + 1 == 5) {
      detail::migrateToDesigns(db);
    } else {
      db.exec(kMigrations[v - 1]);
    }
    if (v + 1 == 4) compactStoredSamples(db);
    db.exec(fmt::format("PRAGMA user_version = {}", v + 1));
    t.commit();
  }
}

/// Schema version 1 in a new file (createSqlite): a new study then passes through every
/// migration, as an old one does.
void detail::createSqliteSchemaV1(SqlConnection& db) {
  db.exec(fmt::format("PRAGMA application_id = {}", kStudyApplicationId));
  db.exec(kSchemaV1);
  db.exec("PRAGMA user_version = 1");
}

void detail::migrateToDesigns(SqlConnection& db) {
  db.exec(kMigrationV4ToV5);
  // Every study before designs is of the paper's form: its plan, from the stored definition
  // and each subject's stored order, says each trial's place (one session, day 0).
  Statement definition(db, "SELECT definition FROM study WHERE id = 1");
  if (!definition.step()) return;  // a new study: its trials are written with their places
  const StudyDefinition study = parseStudy(definition.text(0), db.location() + ":study", "", false);
  std::vector<std::pair<std::string, std::string>> subjects;  // id, mode order
  {
    Statement list(db, "SELECT id, mode_order FROM subjects ORDER BY position");
    while (list.step()) subjects.emplace_back(list.text(0), list.text(1));
  }
  for (const auto& [id, order_json] : subjects) {
    const auto spec = std::find_if(study.subjects.begin(), study.subjects.end(), [&](const auto& s) { return s.id == id; });
    HATTR_THROW_UNLESS(spec != study.subjects.end(), "{}: subject {} is not in the study's definition", db.location(),
                       textExcerpt(id));
    std::vector<guidance::TrainingMode> order;
    for (const auto& m : json::parse(order_json)) order.push_back(guidance::parseMode(m.get<std::string>()));
    for (const TrialPlan& p : planTrials(study, *spec, order)) {
      Statement u(db, "UPDATE trials SET skill = ?, schedule_session = ?, day = ?, block = ? WHERE subject = ? AND "
                      "sequence = ?");
      u.bind(1, p.skill).bind(2, p.session).bind(3, p.day).bind(4, p.block).bind(5, id).bind(6, p.sequence).run();
    }
    Statement g(db, "UPDATE subjects SET group_name = ? WHERE id = ?");
    g.bind(1, spec->group).bind(2, id).run();
  }
}

}  // namespace hattr::session
