// The study store on SQLite (one file, one station): creating and opening the file, reading
// a study another user may be running, and the runner lock that lets one runner at a time
// write it. The queries both stores run are in study_database.cpp.

#include <fcntl.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/session/study_database.hpp"
#include "sql_connection.hpp"
#include "study_database_internal.hpp"

namespace hattr::session {

/// Whether a runner holds the study's lock (a shared-lock probe that is released at once).
bool detail::runnerLockHeld(const std::filesystem::path& file) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const bool held = ::flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK;
  ::close(fd);
  return held;
}

namespace {

using detail::createSqliteSchemaV1;
using detail::migrateSqlite;
using detail::runnerLockHeld;
using detail::scalar;
using detail::SqlConnection;
using detail::Statement;
using detail::Transaction;

sqlite3* openSqliteFile(const std::filesystem::path& file, int flags) {
  return detail::openSqliteFile(file, flags, "the study database");
}

/// Opens a study for reading only. A study in a folder this process cannot write (a shared,
/// read-only copy) is opened immutable, since SQLite could not create the WAL's shared-memory
/// file there; immutable means the file is read alone, so a study whose write-ahead log still
/// holds changes, or that a runner (another user) is writing, is refused, not read stale.
sqlite3* openForReading(const std::filesystem::path& file) {
  const std::filesystem::path folder = file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path();
  if (::access(folder.c_str(), W_OK) == 0) {
    // A writable study is read through a query-only read-write connection: SQLite's WAL and
    // shared-memory files go away when it closes, as they do not after a read-only one.
    if (::access(file.c_str(), W_OK) != 0) return openSqliteFile(file, SQLITE_OPEN_READONLY);
    sqlite3* db = openSqliteFile(file, SQLITE_OPEN_READWRITE);
    sqlite3_exec(db, "PRAGMA query_only = 1", nullptr, nullptr, nullptr);
    return db;
  }
  std::error_code ec;
  const std::filesystem::path wal(file.string() + "-wal");
  HATTR_THROW_UNLESS(!std::filesystem::exists(wal, ec) || std::filesystem::file_size(wal, ec) == 0,
                     "{}: its write-ahead log {} holds changes not yet in the file, and this user cannot write the "
                     "folder: copy the study with its -wal file to a writable folder and read it there",
                     file.string(), wal.string());
  HATTR_THROW_UNLESS(!runnerLockHeld(file), "{}: a runner is writing this study and this user cannot write its "
                     "folder: read it when the run is over", file.string());
  std::string uri = "file:";
  for (const char c : std::filesystem::absolute(file).string()) {
    if (c == '%' || c == '?' || c == '#') {
      uri += fmt::format("%{:02X}", static_cast<unsigned char>(c));
    } else {
      uri += c;
    }
  }
  uri += "?immutable=1";
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(uri.c_str(), &db, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, nullptr) != SQLITE_OK) {
    const std::string message = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    throw InputError(fmt::format("{}: cannot open the study database: {}", file.string(), message));
  }
  return db;
}

/// The exclusive runner lock: flock on the database file itself (independent of SQLite's
/// own POSIX locks on Linux). Returns the descriptor, or throws naming the holder.
int takeRunnerLock(const std::filesystem::path& file, SqlConnection& db) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw Error(fmt::format("{}: cannot open for locking: {}", file.string(), std::strerror(errno)));
  // A reader's probe (runnerLockHeld) holds a shared lock for an instant: try a few times.
  bool locked = false;
  for (int attempt = 0; attempt < 5 && !locked; ++attempt) {
    locked = ::flock(fd, LOCK_EX | LOCK_NB) == 0;
    if (!locked) ::usleep(20'000);
  }
  if (!locked) {
    ::close(fd);
    std::string holder = "another process";
    try {
      Statement s(db, "SELECT pid, host FROM sessions WHERE ended_utc IS NULL ORDER BY id DESC LIMIT 1");
      if (s.step()) holder = fmt::format("process {} on {}", s.integer(0), s.text(1));
    } catch (const Error&) {
    }
    throw InputError(fmt::format("{}: the study is being run by {}; wait for it to finish or stop it first",
                                 file.string(), holder));
  }
  return fd;
}

/// Removes a database file and SQLite's companions (journal, WAL, shared memory); quiet.
void removeDatabaseFiles(const std::filesystem::path& file) noexcept {
  std::error_code ignored;
  for (const char* suffix : {"", "-journal", "-wal", "-shm"}) {
    std::filesystem::remove(std::filesystem::path(file.string() + suffix), ignored);
  }
}

/// Moves a finished database into place without ever replacing a file: link, then unlink.
void publishDatabase(const std::filesystem::path& from, const std::filesystem::path& to) {
  if (::link(from.c_str(), to.c_str()) != 0) {
    const int error = errno;
    if (error == EEXIST) throw InputError(fmt::format("{}: already exists; refusing to overwrite a study database", to.string()));
    throw Error(fmt::format("{}: cannot create the study database: {}", to.string(), std::strerror(error)));
  }
  std::error_code ignored;
  std::filesystem::remove(from, ignored);
}

}  // namespace

StudyDatabase StudyDatabase::createSqlite(const std::filesystem::path& file, const StudyDefinition& study,
                                          const std::map<std::string, std::string>& expert_csv,
                                          const std::function<void(StudyDatabase&)>& fill) {
  // Built under a hidden name beside the file and linked into place only when complete, so a
  // kill, a full disk or a failed fill leaves no stub that blocks the next attempt.
  const std::filesystem::path building =
      file.parent_path() / fmt::format(".{}.creating-{}", file.filename().string(), ::getpid());
  removeDatabaseFiles(building);
  try {
    {
      StudyDatabase database(building, detail::makeSqliteConnection(openSqliteFile(building, SQLITE_OPEN_READWRITE |
                                                                                         SQLITE_OPEN_CREATE),
                                                                    building.string()));
      SqlConnection& db = *database.db_;
      db.exec("PRAGMA journal_mode = WAL");
      db.exec("PRAGMA synchronous = FULL");
      db.exec("PRAGMA foreign_keys = ON");
      {
        Transaction t(db);
        createSqliteSchemaV1(db);
        t.commit();
      }
      migrateSqlite(db, 1);
      {
        Transaction t(db);
        database.writeNewStudy(study, expert_csv);
        t.commit();
      }
      if (fill) fill(database);
      db.exec("PRAGMA wal_checkpoint(TRUNCATE)");
    }  // closed: the WAL is checked in and removed
    publishDatabase(building, file);
  } catch (...) {
    removeDatabaseFiles(building);
    throw;
  }
  return open(file, OpenMode::kReadWrite);
}

StudyDatabase StudyDatabase::openSqlite(const std::filesystem::path& file, OpenMode mode, const StoreOptions& options) {
  HATTR_THROW_UNLESS(std::filesystem::is_regular_file(file), "{}: no such study database (create one with `hattr study init`)",
                     file.string());
  sqlite3* handle = mode == OpenMode::kReadOnly ? openForReading(file) : openSqliteFile(file, SQLITE_OPEN_READWRITE);
  StudyDatabase database(file, detail::makeSqliteConnection(handle, file.string()));
  SqlConnection& db = *database.db_;

  // Is this a hattr study, and one we can read?
  std::int64_t app_id = 0, version = 0;
  try {
    app_id = scalar(db, "PRAGMA application_id");
    version = scalar(db, "PRAGMA user_version");
  } catch (const Error&) {
    const int code = sqlite3_errcode(handle) & 0xff;
    if (code == SQLITE_NOTADB) {
      throw InputError(fmt::format("{}: not a hattr study database (not an SQLite file)", file.string()));
    }
    if (code == SQLITE_CORRUPT) throw InputError(fmt::format("{}: the study database is damaged: {}", file.string(), sqlite3_errmsg(handle)));
    throw Error(fmt::format("{}: cannot read the study database: {}", file.string(), sqlite3_errmsg(handle)));
  }
  HATTR_THROW_UNLESS(app_id == kStudyApplicationId,
                     "{}: not a hattr study database (SQLite application id {:#x}, expected {:#x})", file.string(),
                     app_id, kStudyApplicationId);
  HATTR_THROW_UNLESS(version >= 1 && version <= kStudySchemaVersion,
                     "{}: study schema version {} is {} this build of hattr reads (1 to {}); {}", file.string(), version,
                     version > kStudySchemaVersion ? "newer than" : "not one", kStudySchemaVersion,
                     version > kStudySchemaVersion ? "use a newer hattr" : "the file is damaged");
  HATTR_THROW_UNLESS(mode != OpenMode::kReadOnly || version == kStudySchemaVersion,
                     "{}: study schema version {} is older than this build's {}; it is brought up to date when it is "
                     "opened for writing (`hattr study run` or `hattr study analyze`), and cannot be read as it is",
                     file.string(), version, kStudySchemaVersion);
  if (mode != OpenMode::kReadOnly) {
    db.exec(options.scratch ? "PRAGMA synchronous = OFF" : "PRAGMA synchronous = FULL");
    // A scratch study is one process's, removed once analyzed: it keeps the file's lock (no lock
    // calls for each transaction) and its rollback journal in memory (no journal writes).
    if (options.scratch) {
      db.exec("PRAGMA locking_mode = EXCLUSIVE");
      db.exec("PRAGMA journal_mode = MEMORY");
    }
    db.exec("PRAGMA foreign_keys = ON");
  }
  database.options_ = options;
  if (mode == OpenMode::kRunner) database.lock_fd_ = takeRunnerLock(file, db);
  if (mode != OpenMode::kReadOnly && version < kStudySchemaVersion) migrateSqlite(db, static_cast<int>(version));
  if (mode == OpenMode::kRunner) {
    // We hold the runner lock: anything still marked running died with its process.
    Transaction t(db);
    db.exec("UPDATE trials SET status = 'interrupted', interruptions = interruptions + 1 WHERE status = 'running'");
    db.exec(fmt::format("UPDATE sessions SET ended_utc = '{}' WHERE ended_utc IS NULL", utcNowIso8601()));
    t.commit();
  }
  database.loadDefinition();
  return database;
}

}  // namespace hattr::session
