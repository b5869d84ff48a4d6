#include "hattr/ops/power_run.hpp"

#include <chrono>

namespace hattr::ops {

std::vector<report::ReplicateOutcome> runPowerPart(const sim::PowerStudy& study, int part, int parts,
                                                   const std::function<void(double done, int of)>& progress) {
  std::vector<int> mine;
  for (int r = part; r < study.plan().replicates; r += parts) mine.push_back(r);
  const int of = static_cast<int>(mine.size());
  return study.runReplicates(mine, [&](double done) {
    if (progress) progress(done, of);
  });
}

nlohmann::json powerRunJson(int studies, double seconds, int processes, int threads) {
  return {{"studies", studies}, {"seconds", seconds}, {"processes", processes},
          {"threads_per_process", threads}, {"studies_per_second", studies / seconds}};
}

nlohmann::json PowerAnalysisResult::toJson() const {
  nlohmann::json json = report::powerTableToJson(table);
  json["run"] = powerRunJson(studies, seconds, 1, threads);
  return json;
}

PowerAnalysisResult runPowerAnalysis(const sim::PowerOptions& options,
                                     const std::function<void(double done, int of)>& progress) {
  const sim::PowerStudy study(options);
  const auto started = std::chrono::steady_clock::now();
  std::vector<report::ReplicateOutcome> outcomes = runPowerPart(study, 0, 1, progress);
  PowerAnalysisResult result;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  result.studies = study.plan().replicates;
  result.threads = options.threads;
  result.table = report::summarizePower(study.plan(), std::move(outcomes));
  return result;
}

}  // namespace hattr::ops
