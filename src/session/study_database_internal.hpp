#pragma once
// What the study store's files share (internal to the session module). StudyDatabase is split
// by job: study_database.cpp (the queries both engines run), study_sqlite.cpp (the SQLite
// store: opening, the runner lock), study_postgres.cpp (the PostgreSQL store: schema, leases),
// study_schema.cpp (SQLite's schema and its migrations) and study_samples.cpp (how a trial's
// samples are packed into a block).

#include <cstddef>
#include <filesystem>
#include <string_view>
#include <vector>

#include "hattr/core/channel.hpp"
#include "hattr/core/sample.hpp"
#include "sql_connection.hpp"

namespace hattr::session::detail {

// ---- Schema and migrations (study_schema.cpp) ----------------------------------------------

/// Creates schema version 1 in a new SQLite file (its application id, tables and version), in
/// the caller's transaction; migrateSqlite then brings it up to this build's.
void createSqliteSchemaV1(SqlConnection& db);

/// An SQLite study brought from `from_version` up to this build's schema, a step at a time
/// (each its own transaction).
void migrateSqlite(SqlConnection& db, int from_version);

/// Migration 4 -> 5 on either store: the trials' places in the design and the subjects'
/// groups, filled in from the stored definition; in the caller's transaction.
void migrateToDesigns(SqlConnection& db);

// ---- The SQLite store (study_sqlite.cpp) ----------------------------------------------------

/// Whether a runner holds the study's lock (a shared-lock probe that is released at once).
bool runnerLockHeld(const std::filesystem::path& file);

// ---- Sample packing (study_samples.cpp) -----------------------------------------------------

/// The channels a samples block stores for a profile with `raw` raw channels (none derived).
std::vector<Channel> storedChannels(const RawChannels& raw);

/// Schema 3's rows of little-endian doubles, one row per sample; throws InputError when the
/// block's size does not match.
std::vector<Sample> decodeRowSamples(std::string_view bytes, const RawChannels& raw, std::size_t count);

}  // namespace hattr::session::detail
