#pragma once
// A throwaway PostgreSQL server for the study store's tests: initdb and pg_ctl in a temporary
// folder, listening on a Unix socket in that folder only (no TCP), trust authentication for the
// `postgres` role, removed at the end of the test program. PostgreSQL refuses to run as root,
// and these machines run everything as root: then the server runs as the unprivileged
// `postgres` user that Debian's postgresql package creates (runuser). Missing binaries are a
// test failure that says what to install: the PostgreSQL tests are part of the suite.

#include <pwd.h>
#include <stdlib.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "support/test_support.hpp"

namespace hattr::test {

class PostgresCluster {
 public:
  /// The test program's server, started at the first call (a few seconds).
  static PostgresCluster& shared() {
    static PostgresCluster cluster;
    return cluster;
  }

  /// A new empty database; returns its address (postgresql:///NAME?host=SOCKET_DIR&user=postgres).
  std::string createDatabase(const std::string& prefix) {
    static std::atomic<int> counter{0};
    const std::string name = prefix + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
    run(as_ + tool("createdb") + " -h " + dir_.string() + " -U postgres " + name, "createdb " + name);
    return address(name);
  }
  [[nodiscard]] std::string address(const std::string& database) const {
    return "postgresql:///" + database + "?host=" + dir_.string() + "&user=postgres";
  }
  /// Runs SQL in a database with psql (the tests' way to play a station that misbehaves).
  void sql(const std::string& database, const std::string& statement) const {
    const std::filesystem::path file = dir_ / "statement.sql";
    writeText(file, statement);
    ::chmod(file.c_str(), 0644);
    run(as_ + tool("psql") + " -q -v ON_ERROR_STOP=1 -h " + dir_.string() + " -U postgres -d " + database + " -f " +
            file.string() + " >/dev/null",
        "psql");
  }

  PostgresCluster(const PostgresCluster&) = delete;
  PostgresCluster& operator=(const PostgresCluster&) = delete;

 private:
  PostgresCluster() {
    bin_ = serverBinaries();
    if (::geteuid() == 0) {
      const passwd* user = ::getpwnam("postgres");
      if (!user) {
        throw std::runtime_error("the PostgreSQL tests run as root, and initdb refuses root: expected the unprivileged "
                                 "user `postgres` (Debian's postgresql package creates it: scripts/install-deps)");
      }
      as_ = "runuser -u postgres -- ";
      uid_ = user->pw_uid;
      gid_ = user->pw_gid;
    }
    char pattern[] = "/tmp/hattr-pg-XXXXXX";
    if (!::mkdtemp(pattern)) throw std::runtime_error("mkdtemp failed for the PostgreSQL test server");
    dir_ = pattern;
    if (::geteuid() == 0 && ::chown(dir_.c_str(), uid_, gid_) != 0) {
      throw std::runtime_error("cannot give the PostgreSQL test folder to the postgres user");
    }
    const std::string data = (dir_ / "data").string();
    run(as_ + tool("initdb") + " -D " + data + " --auth=trust --username=postgres --encoding=UTF8 --no-instructions >" +
            (dir_ / "initdb.log").string() + " 2>&1",
        "initdb");
    // Unix socket in the folder only; fsync off: the tests kill stations, never the server.
    run(as_ + tool("pg_ctl") + " -D " + data + " -l " + (dir_ / "server.log").string() + " -w -t 60 -o \"-k " +
            dir_.string() + " -c listen_addresses='' -c fsync=off -c max_connections=60\" start >/dev/null",
        "pg_ctl start");
    started_ = true;
  }
  ~PostgresCluster() {
    if (started_) {
      (void)std::system((as_ + tool("pg_ctl") + " -D " + (dir_ / "data").string() + " -m immediate stop >/dev/null 2>&1").c_str());
    }
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }

  /// The folder of the server's programs: Debian's /usr/lib/postgresql/VERSION/bin (the newest),
  /// else PATH ("").
  static std::filesystem::path serverBinaries() {
    std::error_code ec;
    std::filesystem::path found;
    int newest = -1;
    for (const auto& version : std::filesystem::directory_iterator("/usr/lib/postgresql", ec)) {
      const std::string name = version.path().filename().string();
      const int number = std::atoi(name.c_str());
      if (std::filesystem::exists(version.path() / "bin" / "initdb") && number > newest) {
        newest = number;
        found = version.path() / "bin";
      }
    }
    if (!found.empty()) return found;
    if (std::system("command -v initdb >/dev/null 2>&1 && command -v pg_ctl >/dev/null 2>&1 && "
                    "command -v createdb >/dev/null 2>&1") == 0) {
      return {};
    }
    throw std::runtime_error("the PostgreSQL tests need a PostgreSQL server's initdb, pg_ctl and createdb: not in "
                             "/usr/lib/postgresql/*/bin nor on PATH; install Debian's postgresql package "
                             "(scripts/install-deps)");
  }
  [[nodiscard]] std::string tool(const std::string& name) const { return bin_.empty() ? name : (bin_ / name).string(); }
  void run(const std::string& command, const std::string& what) const {
    if (std::system(command.c_str()) != 0) {
      throw std::runtime_error(what + " failed for the PostgreSQL test server (" + command + "); its log: " +
                               (dir_ / "server.log").string());
    }
  }

  std::filesystem::path bin_;
  std::filesystem::path dir_;
  std::string as_;
  uid_t uid_ = 0;
  gid_t gid_ = 0;
  bool started_ = false;
};

}  // namespace hattr::test
