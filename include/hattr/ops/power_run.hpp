#pragma once
/// A power analysis (`hattr sim power`, Python's `power_analysis`; docs/replication.md) as
/// library calls: one process's share of the replicates (the CLI splits them across MPI
/// ranks or shards and gathers them), and the whole analysis in one process with its table and
/// its run's figures.
///
/// Threads: blocks; the study's own threads run its replicates (PowerOptions::threads), and
/// `progress` is called on one of them at a time.

#include <functional>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/report/power.hpp"
#include "hattr/sim/power.hpp"

namespace hattr::ops {

/// Replicates part, part + parts, part + 2·parts, ... of the study (part in [0, parts)), each
/// the same to the bit wherever it runs. `progress`: replicates run so far, of how many.
std::vector<report::ReplicateOutcome> runPowerPart(const sim::PowerStudy& study, int part, int parts,
                                                   const std::function<void(double done, int of)>& progress = {});

struct PowerAnalysisResult {
  report::PowerTable table;
  int studies = 0;               ///< replicates run
  double seconds = 0.0;          ///< wall time of the replicates
  int threads = 1;
  /// report::powerTableToJson plus run {studies, seconds, processes: 1, threads_per_process,
  /// studies_per_second}, as `hattr sim power --json` prints it.
  [[nodiscard]] nlohmann::json toJson() const;
};

/// The whole analysis in this process. Throws InputError for bad options or study.
PowerAnalysisResult runPowerAnalysis(const sim::PowerOptions& options,
                                     const std::function<void(double done, int of)>& progress = {});

/// The figures of a run for the JSON's "run": {studies, seconds, processes, threads_per_process,
/// studies_per_second}.
nlohmann::json powerRunJson(int studies, double seconds, int processes, int threads);

}  // namespace hattr::ops
