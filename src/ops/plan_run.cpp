#include "hattr/ops/plan_run.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <thread>
#include <tuple>

#include <fmt/format.h>

#include "hattr/core/atomic_file.hpp"
#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"

namespace hattr::ops {
namespace {

constexpr int kStateFormat = 1;

/// A replicate of a design of a search.
struct Key {
  int search = 0;
  int subjects = 0;
  int replicate = 0;
  auto operator<=>(const Key&) const = default;
};
using Outcomes = std::map<Key, double>;  ///< the comparison's p (NaN: nothing to test)

bool sameP(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

/// Records an outcome, refusing one that differs from what is known of the same replicate.
void remember(Outcomes& known, const Key& key, double p, std::string_view where) {
  const auto [it, fresh] = known.emplace(key, p);
  HATTR_THROW_UNLESS(fresh || sameP(it->second, p),
                     "{}: replicate {} of {} subjects (search {}) has p {} here and {} elsewhere: outcomes of another "
                     "build or machine kind cannot be mixed",
                     where, key.replicate, key.subjects, key.search, p, it->second);
}

/// The plan's state folder: plan.json and the writers' outcome lines (ops/plan_run.hpp).
class StateFolder {
 public:
  StateFolder(std::filesystem::path dir, const nlohmann::json& plan, const std::string& writer, bool writes)
      : dir_(std::move(dir)) {
    std::filesystem::create_directories(dir_);
    checkPlan(plan, writes);
    if (writes) openOwn(dir_ / fmt::format("outcomes-{}.jsonl", writer));
  }
  ~StateFolder() {
    if (fd_ >= 0) ::close(fd_);
  }
  StateFolder(const StateFolder&) = delete;
  StateFolder& operator=(const StateFolder&) = delete;

  /// Every writer's complete lines not read before.
  void read(Outcomes& known) {
    for (const auto& entry : std::filesystem::directory_iterator(dir_)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("outcomes-", 0) != 0 || entry.path().extension() != ".jsonl") continue;
      readNew(entry.path(), known);
    }
  }

  /// Appends outcomes to this writer's file and syncs it: once there, they survive a kill.
  void append(const std::vector<std::pair<Key, double>>& fresh) {
    if (fd_ < 0 || fresh.empty()) return;
    std::string text;
    for (const auto& [k, p] : fresh) {
      text += nlohmann::json{{"search", k.search}, {"subjects", k.subjects}, {"replicate", k.replicate},
                             {"p", jsonNumber(p)}}.dump() + "\n";
    }
    for (std::size_t done = 0; done < text.size();) {
      const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) throw Error(fmt::format("{}: cannot write: {}", own_.string(), std::strerror(errno)));
      done += static_cast<std::size_t>(n);
    }
    if (::fdatasync(fd_) != 0) throw Error(fmt::format("{}: cannot sync: {}", own_.string(), std::strerror(errno)));
  }

 private:
  /// plan.json: written by the first writer, else the same plan.
  void checkPlan(const nlohmann::json& plan, bool writes) {
    const std::filesystem::path file = dir_ / "plan.json";
    const nlohmann::json state{{"hattr_plan_state", kStateFormat}, {"plan", plan}};
    if (!std::filesystem::exists(file) && writes) {
      try {
        writeFileAtomically(file, state.dump(1) + "\n", Overwrite::kRefuse);
        return;
      } catch (const InputError&) {  // another shard wrote it first: compare below
      }
    }
    if (!std::filesystem::exists(file)) return;  // an MPI rank but the first: rank 0 writes it
    const nlohmann::json found = parseJsonObject(readTextFile(file), file.string());
    HATTR_THROW_UNLESS(found.value("hattr_plan_state", 0) == kStateFormat && found.contains("plan"),
                       "{}: not a plan's state (expected \"hattr_plan_state\": {}, as `hattr sim plan --state` "
                       "writes)", file.string(), kStateFormat);
    const nlohmann::json& other = found.at("plan");
    if (other == plan) return;
    std::string differs = "?";
    for (const auto& [key, value] : plan.items()) {
      if (!other.contains(key) || other.at(key) != value) {
        differs = key;
        break;
      }
    }
    HATTR_THROW_UNLESS(false, "{}: the folder holds another plan (its \"{}\" differs): expected the same options to "
                       "resume it, or a new --state folder", file.string(), differs);
  }

  /// Opens this writer's file to append, locked against another process of the same writer
  /// name, dropping a last line a kill cut off.
  void openOwn(const std::filesystem::path& file) {
    own_ = file;
    fd_ = ::open(file.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (fd_ < 0) throw Error(fmt::format("{}: cannot open to append: {}", file.string(), std::strerror(errno)));
    try {
      lockOwn(file);
      const std::string text = readTextFile(file);
      const std::size_t end = text.rfind('\n');
      const auto whole = static_cast<off_t>(end == std::string::npos ? 0 : end + 1);
      if (static_cast<std::size_t>(whole) != text.size() && ::ftruncate(fd_, whole) != 0) {
        throw Error(fmt::format("{}: cannot drop its cut-off last line: {}", file.string(), std::strerror(errno)));
      }
    } catch (...) {  // the constructor throws: no destructor closes it
      ::close(fd_);
      fd_ = -1;
      throw;
    }
  }

  /// The writer's lock. A file system without locks (Lustre mounted without flock, some NFS)
  /// runs unlocked: one process per writer name is then the user's to keep.
  void lockOwn(const std::filesystem::path& file) const {
    if (::flock(fd_, LOCK_EX | LOCK_NB) == 0) return;
    const int error = errno;
    if (error == ENOSYS || error == EOPNOTSUPP || error == ENOLCK) return;
    HATTR_THROW_UNLESS(error != EWOULDBLOCK, "{}: another `hattr sim plan` is writing this file now: expected one "
                       "process per writer (give each its own --shard i/N, or another --state folder)", file.string());
    throw Error(fmt::format("{}: cannot lock: {}", file.string(), std::strerror(error)));
  }

  void readNew(const std::filesystem::path& file, Outcomes& known) {
    std::ifstream in(file, std::ios::binary);
    std::uintmax_t& offset = offsets_[file];
    in.seekg(static_cast<std::streamoff>(offset));
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::size_t at = 0;
    for (std::size_t end = text.find('\n'); end != std::string::npos; at = end + 1, end = text.find('\n', at)) {
      ++lines_[file];
      const std::string where = fmt::format("{}:{}", file.string(), lines_[file]);
      const nlohmann::json j = parseJsonObject(std::string_view(text).substr(at, end - at), where);
      readingJson(where, [&] {
        const Key key{j.at("search").get<int>(), j.at("subjects").get<int>(), j.at("replicate").get<int>()};
        HATTR_THROW_UNLESS(key.search >= 0 && key.subjects >= 1 && key.replicate >= 0,
                           "{}: expected a search and a replicate of 0 or more and subjects of 1 or more, got search "
                           "{}, subjects {}, replicate {}", where, key.search, key.subjects, key.replicate);
        const nlohmann::json& p = j.at("p");
        HATTR_THROW_UNLESS(p.is_null() || p.is_number(), "{}: \"p\": expected a number or null, got {}", where, p.dump());
        remember(known, key, p.is_null() ? std::nan("") : p.get<double>(), where);
      });
    }
    offset += at;  // a line still being written is read next time
  }

  std::filesystem::path dir_;
  std::filesystem::path own_;
  int fd_ = -1;
  std::map<std::filesystem::path, std::uintmax_t> offsets_;
  std::map<std::filesystem::path, int> lines_;
};

/// MPI: each rank's outcomes to every rank (four doubles each: search, subjects, replicate, p;
/// exact), in rank order.
std::vector<std::pair<Key, double>> exchangeOutcomes(const PlanRunOptions& options,
                                                     const std::vector<std::pair<Key, double>>& mine) {
  std::vector<double> flat;
  for (const auto& [k, v] : mine) flat.insert(flat.end(), {double(k.search), double(k.subjects), double(k.replicate), v});
  const std::vector<double> all = options.exchange(flat);
  std::vector<std::pair<Key, double>> out;
  for (std::size_t at = 0; at + 4 <= all.size(); at += 4) {
    out.push_back({{static_cast<int>(all[at]), static_cast<int>(all[at + 1]), static_cast<int>(all[at + 2])},
                   all[at + 3]});
  }
  return out;
}

/// The largest design a search's limits allow (per group), or the reason none is.
struct Limit {
  int max_subjects = 0;
  std::string skipped;
};

Limit limitOf(const sim::PlanDesign& design, const PlanRunOptions& o) {
  const report::PlanSearchOptions& s = o.search;
  const double hours = design.labSecondsPerSubject() / 3600.0;
  int most = s.max_subjects;
  if (std::isfinite(hours) && hours > o.max_hours_per_subject) {
    return {0, fmt::format("{}: {:.2f} lab hours per subject, over the limit of {} h", design.label(), hours,
                           o.max_hours_per_subject)};
  }
  if (std::isfinite(hours) && hours > 0.0 && std::isfinite(o.max_lab_hours)) {
    const double allowed = std::floor(o.max_lab_hours / (hours * design.groups()));
    most = static_cast<int>(std::min<double>(most, allowed));
    if (most < s.min_subjects) {
      return {0, fmt::format("{}: the limit of {} lab hours allows {} {} of {:.2f} h, fewer than the smallest design "
                             "({})", design.label(), o.max_lab_hours, std::max(0, most),
                             design.groups() > 1 ? "subjects per group" : "subjects", hours, s.min_subjects)};
    }
  }
  // On the grid: min, min + step, ...
  return {s.min_subjects + (most - s.min_subjects) / s.step * s.step, {}};
}

nlohmann::json limitJson(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

void checkRunOptions(const std::vector<PlanSearchSpec>& searches, const PlanRunOptions& options) {
  options.search.check();
  HATTR_THROW_UNLESS(options.alpha > 0.0 && options.alpha < 1.0, "--alpha: expected a level in (0, 1), got {}",
                     options.alpha);
  HATTR_THROW_UNLESS(options.parts >= 1 && options.part >= 0 && options.part < options.parts,
                     "plan: part {} of {}: expected 0 <= part < parts", options.part, options.parts);
  HATTR_THROW_UNLESS(options.parts == 1 || options.exchange || !options.state.empty(),
                     "--shard: shards share their replicates through a state folder: expected --state DIR");
  HATTR_THROW_UNLESS(!searches.empty(), "plan: expected at least one design to search");
}

/// What the plan is (plan.json's "plan"): a resume and every shard must have the same.
nlohmann::json planDefinition(const std::vector<PlanSearchSpec>& searches, const PlanRunOptions& options) {
  nlohmann::json designs = nlohmann::json::array();
  for (const auto& s : searches) designs.push_back({{"design", s.design->identity()}, {"hypothesis", s.hypothesis}});
  nlohmann::json plan = {{"comparison", options.comparison},
                         {"outcome", options.outcome},
                         {"analysis", options.analysis},
                         {"alpha", options.alpha},
                         {"search", report::planSearchOptionsToJson(options.search)},
                         {"limits",
                          {{"max_hours_per_subject", limitJson(options.max_hours_per_subject)},
                           {"max_lab_hours", limitJson(options.max_lab_hours)}}},
                         {"designs", designs}};
  for (const auto& [key, value] : options.extra.items()) plan[key] = value;
  return plan;
}

/// Runs the batches one search asks for, this process's share of each, sharing outcomes with
/// the other parts (MPI or shards) and keeping them in the state folder.
class BatchRunner {
 public:
  BatchRunner(const PlanRunOptions& options, StateFolder* state, Outcomes& known)
      : options_(options), state_(state), known_(known) {}
  [[nodiscard]] int replicatesRun() const noexcept { return run_; }

  /// The search to its end: report::PlanSearch fed what is known, then each batch it asks for.
  report::PlanSearchResult search(int index, const sim::PlanDesign& design, const report::PlanSearchOptions& o) {
    report::PlanSearch search(o);
    feed(index, search);
    while (const std::optional<report::PlanRequest> request = search.next()) {
      if (options_.log) {
        options_.log(fmt::format("plan: {}: {} subjects, replicates {}-{}", design.label(), request->subjects,
                                 request->first, request->first + request->count - 1));
      }
      runBatch(index, design, search, *request);
      feed(index, search);
    }
    return search.result();
  }

 private:
  /// The known outcomes of search `index` on its grid, to the search.
  void feed(int index, report::PlanSearch& search) const {
    const report::PlanSearchOptions& o = search.options();
    for (auto it = known_.lower_bound({index, 0, 0}); it != known_.end() && it->first.search == index; ++it) {
      const Key& k = it->first;
      const bool on_grid = k.subjects >= o.min_subjects && k.subjects <= o.max_subjects &&
                           (k.subjects - o.min_subjects) % o.step == 0 && k.replicate < o.max_replicates;
      if (on_grid && !search.has(k.subjects, k.replicate)) {
        search.record(k.subjects, k.replicate, std::isfinite(it->second) && it->second < options_.alpha);
      }
    }
  }

  void runBatch(int index, const sim::PlanDesign& design, const report::PlanSearch& search,
                const report::PlanRequest& request) {
    // This process's share of the batch, of those not known yet.
    std::vector<int> needed, mine;
    for (int r = request.first; r < request.first + request.count; ++r) {
      if (search.has(request.subjects, r)) continue;
      needed.push_back(r);
      if (r % options_.parts == options_.part) mine.push_back(r);
    }
    const std::vector<double> p = design.pValues(request.subjects, mine, {});
    run_ += static_cast<int>(mine.size());
    std::vector<std::pair<Key, double>> fresh;
    for (std::size_t k = 0; k < mine.size(); ++k) fresh.push_back({{index, request.subjects, mine[k]}, p[k]});
    if (options_.exchange) fresh = exchanged(fresh);
    if (state_) state_->append(fresh);
    for (const auto& [k, v] : fresh) remember(known_, k, v, "plan");
    if (!options_.exchange && options_.parts > 1) awaitOtherShards(index, design, request, needed);
  }

  /// MPI: every rank's outcomes to every rank; the first writes them all.
  std::vector<std::pair<Key, double>> exchanged(const std::vector<std::pair<Key, double>>& mine) const {
    return exchangeOutcomes(options_, mine);
  }

  /// Shards: the others' share of the batch, from their files.
  void awaitOtherShards(int index, const sim::PlanDesign& design, const report::PlanRequest& request,
                        const std::vector<int>& needed) {
    const auto since = std::chrono::steady_clock::now();
    const auto missing = [&] {
      return std::count_if(needed.begin(), needed.end(),
                           [&](int r) { return !known_.contains({index, request.subjects, r}); });
    };
    for (state_->read(known_); missing() > 0; state_->read(known_)) {
      const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
      if (waited > options_.shard_wait_s) {
        throw Error(fmt::format("shard {}/{}: waited {:.0f} s for {} replicates of {} subjects ({}) from the other "
                                "shards: are they running on the same --state folder?",
                                options_.part, options_.parts, waited, missing(), request.subjects, design.label()));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }

  const PlanRunOptions& options_;
  StateFolder* state_;
  Outcomes& known_;
  int run_ = 0;
};

}  // namespace

PlanRunResult runPlan(std::vector<PlanSearchSpec>& searches, const PlanRunOptions& options) {
  const auto started = std::chrono::steady_clock::now();
  checkRunOptions(searches, options);
  // What the plan is, and each search's limits.
  PlanRunResult out;
  report::PlanReport& report = out.report;
  std::vector<Limit> limits;
  for (const auto& s : searches) {
    limits.push_back(limitOf(*s.design, options));
    if (!limits.back().skipped.empty()) report.skipped.push_back(limits.back().skipped);
  }
  HATTR_THROW_UNLESS(report.skipped.size() < searches.size(), "the limits leave no design to search: {}",
                     fmt::join(report.skipped, "; "));
  report.plan = planDefinition(searches, options);

  // The outcomes kept from before, and where this process keeps its own.
  std::optional<StateFolder> state;
  const std::string writer = options.exchange || options.parts == 1
                                 ? std::string("main")
                                 : fmt::format("shard-{}-of-{}", options.part, options.parts);
  // Under MPI only the writing rank (0) opens the folder, and sends what it read to the others:
  // the folder need not be seen by every node. (A rank that fails aborts them all.)
  if (!options.state.empty() && (options.writes_state || !options.exchange)) {
    state.emplace(options.state, report.plan, writer, options.writes_state);
  }
  Outcomes known;
  if (state) state->read(known);
  if (options.exchange) {
    const std::vector<std::pair<Key, double>> read(known.begin(), known.end());
    for (const auto& [k, v] : exchangeOutcomes(options, options.writes_state ? read : decltype(read){})) {
      remember(known, k, v, "plan");
    }
  }

  BatchRunner batches(options, state ? &*state : nullptr, known);
  for (std::size_t i = 0; i < searches.size(); ++i) {
    if (!limits[i].skipped.empty()) continue;
    const sim::PlanDesign& design = *searches[i].design;
    report::PlanSearchOptions search_options = options.search;
    search_options.max_subjects = limits[i].max_subjects;
    report.searches.push_back({design.label(), searches[i].hypothesis, design.identity(), design.groups(),
                               design.labSecondsPerSubject(), limits[i].max_subjects,
                               batches.search(static_cast<int>(i), design, search_options)});
  }
  out.replicates_run = batches.replicatesRun();
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return out;
}

}  // namespace hattr::ops
