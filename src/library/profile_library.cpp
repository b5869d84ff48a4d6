// The profile library's store: one table of profiles with their labels and samples, on the
// study store's SQL layer (SQLite or PostgreSQL), each change one transaction.

#include "hattr/library/profile_library.hpp"

#include <algorithm>
#include <cctype>
#include <set>
#include <unistd.h>

#include <fmt/format.h>
#include <sqlite3.h>

#include "hattr/core/error.hpp"
#include "hattr/io/sample_codec.hpp"
#include "hattr/session/study_database.hpp"
#include "session/sql_connection.hpp"

namespace hattr::library {

using session::detail::scalar;
using session::detail::SqlConnection;
using session::detail::SqlDialect;
using session::detail::Statement;
using session::detail::Transaction;

std::string_view authenticityName(Authenticity a) { return a == Authenticity::kGenuine ? "genuine" : "imitation"; }

Authenticity parseAuthenticity(std::string_view name, std::string_view where) {
  if (name == "genuine") return Authenticity::kGenuine;
  if (name == "imitation") return Authenticity::kImitation;
  throw InputError(fmt::format("{}: authenticity: expected genuine or imitation, got \"{}\"", where, name));
}

bool EntryFilter::matches(const EntryLabels& l) const {
  return (!person || *person == l.person) && (!skill || *skill == l.skill) && (!session || *session == l.session) &&
         (!authenticity || *authenticity == l.authenticity);
}

namespace {

bool printable(std::string_view text) {
  return std::all_of(text.begin(), text.end(), [](char c) { return static_cast<unsigned char>(c) >= 0x20 && c != 0x7f; });
}

bool isoDate(std::string_view d) {
  if (d.size() != 10 || d[4] != '-' || d[7] != '-') return false;
  for (std::size_t i : {0u, 1u, 2u, 3u, 5u, 6u, 8u, 9u}) {
    if (!std::isdigit(static_cast<unsigned char>(d[i]))) return false;
  }
  return true;
}

}  // namespace

void checkLabels(const EntryLabels& l, std::string_view where) {
  const std::pair<std::string_view, const std::string*> required[] = {{"key", &l.key}, {"person", &l.person}, {"skill", &l.skill}};
  for (const auto& [name, value] : required) {
    HATTR_THROW_UNLESS(!value->empty(), "{}: {}: expected a name, got nothing", where, name);
  }
  const std::pair<std::string_view, const std::string*> texts[] = {
      {"key", &l.key},         {"person", &l.person}, {"skill", &l.skill}, {"session", &l.session}, {"device", &l.device},
      {"source", &l.source},   {"imitator", &l.imitator}, {"mode", &l.mode}};
  for (const auto& [name, value] : texts) {
    HATTR_THROW_UNLESS(printable(*value), "{}: {}: expected printable text, got a control character in \"{}\"", where,
                       name, *value);
  }
  HATTR_THROW_UNLESS(l.date.empty() || isoDate(l.date), "{}: date: expected YYYY-MM-DD or nothing, got \"{}\"", where,
                     l.date);
  HATTR_THROW_UNLESS(l.imitator.empty() || l.authenticity == Authenticity::kImitation,
                     "{}: imitator \"{}\" given for a genuine profile; expected an imitation, or no imitator", where,
                     l.imitator);
}

namespace {

// ---- Schema ---------------------------------------------------------------------------------

/// The schema, in the SQL both engines take but for the id column and the blob's type.
std::string schemaSql(SqlDialect dialect) {
  const bool pg = dialect == SqlDialect::kPostgres;
  return fmt::format(R"(
CREATE TABLE library_meta (name TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE profiles (
  id {} PRIMARY KEY,
  key TEXT NOT NULL UNIQUE,
  person TEXT NOT NULL,
  skill TEXT NOT NULL,
  session TEXT NOT NULL,
  recorded_on TEXT NOT NULL,
  device TEXT NOT NULL,
  source TEXT NOT NULL,
  authenticity TEXT NOT NULL CHECK (authenticity IN ('genuine', 'imitation')),
  imitator TEXT NOT NULL,
  mode TEXT NOT NULL,
  added_utc TEXT NOT NULL,
  sample_count BIGINT NOT NULL,
  raw_pressure INTEGER NOT NULL,
  raw_tilt INTEGER NOT NULL,
  metadata TEXT NOT NULL,
  samples {} NOT NULL
);
CREATE INDEX profiles_skill_person ON profiles (skill, person);
)",
                     pg ? "BIGSERIAL" : "INTEGER", pg ? "BYTEA" : "BLOB");
}

sqlite3* openSqlite(const std::filesystem::path& file, int flags) {
  return session::detail::openSqliteFile(file, flags, "the profile library");
}

std::unique_ptr<SqlConnection> connect(const std::string& location, bool create, bool read_only) {
  if (session::detail::isPostgresLocation(location)) return session::detail::connectPostgres(location);
  const int flags = read_only ? SQLITE_OPEN_READONLY : SQLITE_OPEN_READWRITE | (create ? SQLITE_OPEN_CREATE : 0);
  auto db = session::detail::makeSqliteConnection(openSqlite(location, flags), location);
  if (!read_only) db->exec("PRAGMA journal_mode = WAL; PRAGMA synchronous = FULL;");
  return db;
}

/// The schema version a connection's library has; InputError if it is not a library.
int schemaVersionOf(SqlConnection& db) {
  std::string why = "no schema_version";
  try {
    Statement s(db, "SELECT value FROM library_meta WHERE name = 'schema_version'");
    if (s.step()) return std::stoi(s.text(0));
  } catch (const std::exception& e) {
    why = e.what();
  }
  throw InputError(fmt::format("{}: not a hattr profile library ({}); make one with `hattr library init`", db.location(),
                               why));
}

void createSchema(SqlConnection& db) {
  Transaction t(db);
  db.exec(schemaSql(db.dialect()));
  Statement(db, "INSERT INTO library_meta (name, value) VALUES ('schema_version', ?)")
      .bind(1, std::to_string(kLibrarySchemaVersion))
      .run();
  Statement(db, "INSERT INTO library_meta (name, value) VALUES ('created_utc', ?)").bind(1, utcNowIso8601()).run();
  t.commit();
}

constexpr std::string_view kEntryColumns =
    "id, key, person, skill, session, recorded_on, device, source, authenticity, imitator, mode, added_utc, "
    "sample_count, raw_pressure, raw_tilt, metadata";

LibraryEntry readEntry(const Statement& s, const std::string& location) {
  LibraryEntry e;
  e.id = s.integer(0);
  e.labels = {.key = s.text(1), .person = s.text(2), .skill = s.text(3), .session = s.text(4), .date = s.text(5),
              .device = s.text(6), .source = s.text(7),
              .authenticity = parseAuthenticity(s.text(8), fmt::format("{}: entry {}", location, s.text(1))),
              .imitator = s.text(9), .mode = s.text(10)};
  e.added_utc = s.text(11);
  e.samples = static_cast<std::size_t>(std::max<std::int64_t>(0, s.integer(12)));
  e.raw = {s.integer(13) != 0, s.integer(14) != 0};
  const ProfileMetadata meta =
      session::parseProfileMetadataJson(s.text(15), fmt::format("{}: entry {}: metadata", location, e.labels.key));
  e.rate_hz = meta.nominal_rate_hz;
  const auto duration = meta.extra.find("library_duration_s");
  try {
    e.duration_s = duration == meta.extra.end() ? 0.0 : std::stod(duration->second);
  } catch (const std::exception&) {
    throw InputError(fmt::format("{}: entry {}: metadata library_duration_s: expected a number, got \"{}\"", location,
                                 e.labels.key, duration->second));
  }
  return e;
}

}  // namespace

// ---- ProfileLibrary ---------------------------------------------------------------------------

ProfileLibrary::ProfileLibrary(std::unique_ptr<SqlConnection> db) : db_(std::move(db)) {}
ProfileLibrary::ProfileLibrary(ProfileLibrary&&) noexcept = default;
ProfileLibrary& ProfileLibrary::operator=(ProfileLibrary&&) noexcept = default;
ProfileLibrary::~ProfileLibrary() = default;

const std::string& ProfileLibrary::location() const { return db_->location(); }

ProfileLibrary ProfileLibrary::create(const std::string& location) {
  if (session::detail::isPostgresLocation(location)) {
    auto db = connect(location, true, false);
    const bool exists = scalar(*db, "SELECT COUNT(*) FROM information_schema.tables WHERE table_name = 'library_meta' "
                                    "AND table_schema = current_schema()") > 0;
    HATTR_THROW_UNLESS(!exists, "{}: already holds a profile library; expected a database without one", location);
    createSchema(*db);
    return ProfileLibrary(std::move(db));
  }
  // Built beside its place and moved in: a crash leaves no half-made library under the name.
  const std::filesystem::path file(location);
  HATTR_THROW_UNLESS(!std::filesystem::exists(file), "{}: already exists; expected a new file for the profile library",
                     location);
  const std::filesystem::path building = file.string() + fmt::format(".building-{}", ::getpid());
  std::filesystem::remove(building);
  try {
    {
      auto db = session::detail::makeSqliteConnection(openSqlite(building, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE),
                                                      building.string());
      createSchema(*db);
    }
    std::error_code ec;
    std::filesystem::create_hard_link(building, file, ec);  // fails if another made `file` meanwhile
    HATTR_THROW_UNLESS(!ec, "{}: cannot create the profile library: {}", location, ec.message());
    std::filesystem::remove(building);
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(building, ignored);
    throw;
  }
  return open(location);
}

ProfileLibrary ProfileLibrary::open(const std::string& location, bool read_only) {
  if (!session::detail::isPostgresLocation(location)) {
    HATTR_THROW_UNLESS(std::filesystem::is_regular_file(location),
                       "{}: no such profile library; make one with `hattr library init {}`", location, location);
  }
  auto db = connect(location, false, read_only);
  const int version = schemaVersionOf(*db);
  HATTR_THROW_UNLESS(version <= kLibrarySchemaVersion,
                     "{}: a profile library of schema {}, newer than this hattr reads (schema {}); use the hattr "
                     "release that wrote it, or a newer one",
                     location, version, kLibrarySchemaVersion);
  return ProfileLibrary(std::move(db));
}

std::vector<std::int64_t> ProfileLibrary::add(std::span<const std::pair<EntryLabels, HapticProfile>> entries) {
  // Everything is checked before the first row is written.
  std::set<std::string> keys;
  for (const auto& [labels, profile] : entries) {
    const std::string where = fmt::format("{}: entry {}", location(), labels.key);
    checkLabels(labels, where);
    HATTR_THROW_UNLESS(!profile.empty(), "{}: the profile has no samples; expected at least one", where);
    HATTR_THROW_UNLESS(keys.insert(labels.key).second, "{}: the key is given twice; expected each key once", where);
  }
  Transaction t(*db_);
  std::vector<std::int64_t> ids;
  ids.reserve(entries.size());
  for (const auto& [labels, profile] : entries) {
    Statement taken(*db_, "SELECT person, skill FROM profiles WHERE key = ?");
    taken.bind(1, labels.key);
    if (taken.step()) {
      throw InputError(fmt::format("{}: entry {} is already in the library (person {}, skill {}); expected a new key "
                                   "(remove the old entry first to replace it)",
                                   location(), labels.key, taken.text(0), taken.text(1)));
    }
    ProfileMetadata meta = profile.metadata();
    meta.extra["library_duration_s"] = fmt::format("{}", profile.duration_s());
    Statement s(*db_,
                "INSERT INTO profiles (key, person, skill, session, recorded_on, device, source, authenticity, "
                "imitator, mode, added_utc, sample_count, raw_pressure, raw_tilt, metadata, samples) "
                "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?) RETURNING id");
    s.bind(1, labels.key).bind(2, labels.person).bind(3, labels.skill).bind(4, labels.session).bind(5, labels.date);
    s.bind(6, labels.device).bind(7, labels.source).bind(8, std::string(authenticityName(labels.authenticity)));
    s.bind(9, labels.imitator).bind(10, labels.mode).bind(11, utcNowIso8601());
    s.bind(12, static_cast<std::int64_t>(profile.size()));
    s.bind(13, profile.rawChannels().pressure ? 1 : 0).bind(14, profile.rawChannels().tilt ? 1 : 0);
    s.bind(15, session::profileMetadataJson(meta));
    s.bindBlob(16, session::encodeTrialSamples(profile));
    HATTR_THROW_UNLESS(s.step(), "{}: entry {}: the store returned no id", location(), labels.key);
    ids.push_back(s.integer(0));
  }
  t.commit();
  return ids;
}

std::int64_t ProfileLibrary::add(const EntryLabels& labels, const HapticProfile& profile) {
  const std::pair<EntryLabels, HapticProfile> one[] = {{labels, profile}};
  return add(one).front();
}

std::vector<LibraryEntry> ProfileLibrary::list(const EntryFilter& filter) const {
  // Filtered in SQL on the indexed columns, the rest here.
  std::string sql = fmt::format("SELECT {} FROM profiles", kEntryColumns);
  if (filter.skill) sql += " WHERE skill = ?";
  sql += " ORDER BY person, skill, session, key";
  Statement s(*db_, sql);
  if (filter.skill) s.bind(1, *filter.skill);
  std::vector<LibraryEntry> out;
  while (s.step()) {
    LibraryEntry e = readEntry(s, location());
    if (filter.matches(e.labels)) out.push_back(std::move(e));
  }
  return out;
}

LibraryEntry ProfileLibrary::entry(std::string_view key) const {
  Statement s(*db_, fmt::format("SELECT {} FROM profiles WHERE key = ?", kEntryColumns));
  s.bind(1, std::string(key));
  HATTR_THROW_UNLESS(s.step(), "{}: no entry {}; `hattr library list {}` shows the keys", location(), key, location());
  return readEntry(s, location());
}

HapticProfile ProfileLibrary::profile(std::int64_t id) const {
  Statement s(*db_, "SELECT key, metadata, raw_pressure, raw_tilt, sample_count, samples FROM profiles WHERE id = ?");
  s.bind(1, id);
  HATTR_THROW_UNLESS(s.step(), "{}: no entry with id {}", location(), id);
  const std::string where = fmt::format("{}: entry {}", location(), s.text(0));
  ProfileMetadata meta = session::parseProfileMetadataJson(s.text(1), where + ": metadata");
  meta.extra.erase("library_duration_s");
  const RawChannels raw{s.integer(2) != 0, s.integer(3) != 0};
  try {
    const std::string_view blob = s.blob(5);
    const auto samples = session::decodeTrialSamples(blob, io::sampleEncodingOf(blob), raw,
                                                     static_cast<std::size_t>(std::max<std::int64_t>(0, s.integer(4))));
    HapticProfile profile(std::move(meta), raw);
    profile.reserve(samples.size());
    for (const Sample& sample : samples) profile.append(sample);
    return profile;
  } catch (const std::exception& e) {
    throw InputError(fmt::format("{}: the stored samples are damaged: {}", where, e.what()));
  }
}

HapticProfile ProfileLibrary::profile(std::string_view key) const { return profile(entry(key).id); }

void ProfileLibrary::remove(std::span<const std::string> keys) {
  Transaction t(*db_);
  for (const std::string& key : keys) {
    Statement s(*db_, "DELETE FROM profiles WHERE key = ?");
    s.bind(1, key).run();
    HATTR_THROW_UNLESS(s.changes() == 1, "{}: no entry {} (nothing was removed); `hattr library list {}` shows the keys",
                       location(), key, location());
  }
  t.commit();
}

std::optional<std::string> ProfileLibrary::setting(std::string_view name) const {
  Statement s(*db_, "SELECT value FROM library_meta WHERE name = ?");
  s.bind(1, "setting:" + std::string(name));
  if (!s.step()) return std::nullopt;
  return s.text(0);
}

void ProfileLibrary::setSetting(std::string_view name, std::string_view value) {
  const std::pair<std::string, std::string> one[] = {{std::string(name), std::string(value)}};
  setSettings(one);
}

void ProfileLibrary::setSettings(std::span<const std::pair<std::string, std::string>> settings) {
  Transaction t(*db_);
  for (const auto& [name, value] : settings) {
    Statement(*db_,
              "INSERT INTO library_meta (name, value) VALUES (?, ?) ON CONFLICT (name) DO UPDATE SET value = excluded.value")
        .bind(1, "setting:" + name)
        .bind(2, value)
        .run();
  }
  t.commit();
}

bool isDatabaseAddress(std::string_view location) { return session::detail::isPostgresLocation(location); }

std::vector<std::string> ProfileLibrary::persons(std::string_view skill) const {
  Statement s(*db_, skill.empty() ? "SELECT DISTINCT person FROM profiles ORDER BY person"
                                  : "SELECT DISTINCT person FROM profiles WHERE skill = ? ORDER BY person");
  if (!skill.empty()) s.bind(1, std::string(skill));
  std::vector<std::string> out;
  while (s.step()) out.push_back(s.text(0));
  return out;
}

}  // namespace hattr::library
