#pragma once
// The study store's two engines behind one small interface: SQLite (a file, one station) and
// PostgreSQL (a server, many stations). The study's queries are written once, in the SQL both
// engines accept: `?` placeholders (PostgreSQL's connection numbers them), `ON CONFLICT` for
// upserts, `RETURNING` for new ids. What differs (schema creation, locking and leases) is
// chosen by dialect() in study_database.cpp, and lives in study_sqlite.cpp and
// study_postgres.cpp. Internal to the session module.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

struct sqlite3;

namespace hattr::session::detail {

enum class SqlDialect { kSqlite, kPostgres };

/// One statement: bind its parameters (1-based), then step through its rows. A text or blob
/// column's view stays valid until the next step or the statement's end.
class SqlStatement {
 public:
  virtual ~SqlStatement() = default;
  virtual SqlStatement& bind(int i, std::int64_t v) = 0;
  virtual SqlStatement& bind(int i, std::string_view text) = 0;
  virtual SqlStatement& bindNull(int i) = 0;
  virtual SqlStatement& bindBlob(int i, std::string_view bytes) = 0;
  SqlStatement& bind(int i, int v) { return bind(i, static_cast<std::int64_t>(v)); }
  /// Steps once (the first step runs the statement): true if a row is available.
  virtual bool step() = 0;
  void run() {
    while (step()) {
    }
  }
  /// Rows the statement changed (after it ran).
  [[nodiscard]] virtual std::int64_t changes() const = 0;
  [[nodiscard]] virtual std::int64_t integer(int col) const = 0;
  [[nodiscard]] virtual bool isNull(int col) const = 0;
  [[nodiscard]] virtual std::string_view textView(int col) const = 0;
  [[nodiscard]] std::string text(int col) const { return std::string(textView(col)); }
  [[nodiscard]] virtual std::string_view blob(int col) const = 0;
};

class SqlConnection {
 public:
  virtual ~SqlConnection() = default;
  [[nodiscard]] virtual SqlDialect dialect() const = 0;
  /// Where the study is, for messages: a file, or a postgresql:// address (never a password).
  [[nodiscard]] virtual const std::string& location() const = 0;
  [[nodiscard]] virtual std::unique_ptr<SqlStatement> prepare(std::string_view sql) = 0;
  /// Runs statements without parameters or rows (a script).
  virtual void exec(std::string_view sql) = 0;

  /// Begins a transaction that writes (SQLite: takes the write lock at once); inside another,
  /// a savepoint, so that a write that makes its own transaction can be part of a larger one.
  void begin() {
    if (depth_ == 0) {
      beginWrite();
    } else {
      exec(savepoint("SAVEPOINT", 1));
    }
    ++depth_;
  }
  /// Ends the innermost transaction; rollback() never throws.
  void commit() {
    if (depth_ == 1) {
      commitWrite();
    } else {
      exec(savepoint("RELEASE SAVEPOINT"));
    }
    --depth_;
  }
  void rollback() noexcept {
    if (depth_ == 0) return;
    --depth_;
    if (depth_ == 0) {
      rollbackWrite();
    } else {
      try {
        exec(savepoint("ROLLBACK TO SAVEPOINT", 1) + "; " + savepoint("RELEASE SAVEPOINT", 1));
      } catch (...) {  // the outer transaction fails and rolls back in turn
      }
    }
  }

 protected:
  virtual void beginWrite() = 0;
  virtual void commitWrite() = 0;
  virtual void rollbackWrite() noexcept = 0;

 private:
  [[nodiscard]] std::string savepoint(std::string_view verb, int above = 0) const {
    return std::string(verb) + " hattr_" + std::to_string(depth_ + above);
  }
  int depth_ = 0;
};

/// A statement on a connection, used as a value.
class Statement {
 public:
  Statement(SqlConnection& db, std::string_view sql) : s_(db.prepare(sql)) {}
  template <class T>
  Statement& bind(int i, const T& v) {
    s_->bind(i, v);
    return *this;
  }
  Statement& bind(int i, const std::string& v) {
    s_->bind(i, std::string_view(v));
    return *this;
  }
  Statement& bind(int i, const char* v) {
    s_->bind(i, std::string_view(v));
    return *this;
  }
  Statement& bindNull(int i) {
    s_->bindNull(i);
    return *this;
  }
  Statement& bindBlob(int i, std::string_view v) {
    s_->bindBlob(i, v);
    return *this;
  }
  bool step() { return s_->step(); }
  void run() { s_->run(); }
  [[nodiscard]] std::int64_t changes() const { return s_->changes(); }
  [[nodiscard]] std::int64_t integer(int col) const { return s_->integer(col); }
  [[nodiscard]] bool isNull(int col) const { return s_->isNull(col); }
  [[nodiscard]] std::string text(int col) const { return s_->text(col); }
  [[nodiscard]] std::string_view blob(int col) const { return s_->blob(col); }

 private:
  std::unique_ptr<SqlStatement> s_;
};

/// A write transaction that rolls back unless committed.
class Transaction {
 public:
  explicit Transaction(SqlConnection& db) : db_(db) { db_.begin(); }
  ~Transaction() {
    if (!done_) db_.rollback();
  }
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  void commit() {
    db_.commit();
    done_ = true;
  }

 private:
  SqlConnection& db_;
  bool done_ = false;
};

/// The first column of the first row (0 when there is none).
inline std::int64_t scalar(SqlConnection& db, std::string_view sql) {
  Statement s(db, sql);
  return s.step() ? s.integer(0) : 0;
}

// ---- SQLite ---------------------------------------------------------------------------------

/// Takes an open SQLite handle (closed with the connection); `location` is its file.
std::unique_ptr<SqlConnection> makeSqliteConnection(sqlite3* db, std::string location);
/// The handle under an SQLite connection (for what only SQLite has: pragmas' errors, WAL).
sqlite3* sqliteHandle(SqlConnection& db);
/// Opens an SQLite file with sqlite3_open_v2's `flags`, waiting up to 5 s for another
/// connection's lock; InputError naming the file and `what` it is ("the study database") when it
/// cannot.
sqlite3* openSqliteFile(const std::filesystem::path& file, int flags, std::string_view what);

// ---- PostgreSQL -------------------------------------------------------------------------------

/// Whether `location` names a PostgreSQL study (postgresql:// or postgres://).
bool isPostgresLocation(std::string_view location);
/// Connects to a PostgreSQL study. A malformed address, or one that carries a password
/// (credentials belong in libpq's password file, service file or environment), is an
/// InputError; a server that cannot be reached is an Error naming the address.
std::unique_ptr<SqlConnection> connectPostgres(const std::string& location);

}  // namespace hattr::session::detail
