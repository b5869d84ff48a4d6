#pragma once
/// Planning a study (`hattr sim plan`; docs/simulation.md, "Planning a study") as library
/// calls: the searches of report/plan.hpp over the designs of sim/plan.hpp, their replicates
/// run a batch at a time, shared among processes (MPI ranks, or shards on one folder), kept
/// line by line in a state folder so that a killed plan resumes where it stopped with the same
/// answer.
///
/// The state folder holds plan.json (what the plan is: a resume, and every shard, must be the
/// same plan) and one outcomes-WHO.jsonl per writer, a line per replicate: {"search", "subjects",
/// "replicate", "p"}. Outcomes depend only on the plan, the design and the replicate, so any
/// process may use any file's lines; a last line cut off by a kill is dropped.

#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/report/plan.hpp"
#include "hattr/sim/plan.hpp"

namespace hattr::ops {

/// One search: a design, and the hypothesis its subjects learn under (empty: none named).
struct PlanSearchSpec {
  std::unique_ptr<sim::PlanDesign> design;
  std::string hypothesis;
};

struct PlanRunOptions {
  report::PlanSearchOptions search;
  double alpha = 0.05;
  std::string comparison = "mode";
  std::string outcome = "shape";
  std::string analysis;           ///< in words, for the report
  double max_hours_per_subject = std::numeric_limits<double>::infinity();
  double max_lab_hours = std::numeric_limits<double>::infinity();  ///< over all subjects
  nlohmann::json extra;           ///< more of what makes the plan (kept in plan.json)
  std::filesystem::path state;    ///< the state folder; empty: nothing kept
  /// This process's share of each batch: replicates r with r mod parts = part.
  int part = 0;
  int parts = 1;
  /// MPI: gives every rank's new outcomes (flat: search, subjects, replicate, p) to every rank.
  /// Null: the parts are shards that read each other's outcomes from the state folder.
  std::function<std::vector<double>(const std::vector<double>&)> exchange;
  /// False on MPI ranks but the first, which alone opens the state folder: it reads it, sends
  /// what it read to the others (through `exchange`) and writes for all.
  bool writes_state = true;
  double shard_wait_s = 3600.0;   ///< a shard's longest wait for the others' replicates
  /// A line of what is run, as it starts (e.g. for a terminal).
  std::function<void(const std::string&)> log;
};

struct PlanRunResult {
  report::PlanReport report;
  int replicates_run = 0;  ///< run by this process, now (not read from the state)
  double seconds = 0.0;
};

/// The plan. Throws InputError for bad options, limits that no design meets, or a state folder
/// that holds another plan, an unreadable line, or a writer of the same name at work (each
/// writer holds a lock on its own file).
[[nodiscard]] PlanRunResult runPlan(std::vector<PlanSearchSpec>& searches, const PlanRunOptions& options);

}  // namespace hattr::ops
