#pragma once
/// The profile library's evaluation as a report (`hattr library evaluate --out DIR`;
/// docs/library.md): text for the terminal, JSON, and a folder with report.html (the DET figures
/// inline, self-contained), report.md, figures/*.svg, results.csv (a row per feature set and
/// split), scores.csv (every verification score) and results.json. Not for the servo thread.

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "hattr/library/evaluation.hpp"

namespace hattr::report {

/// The results as `hattr library evaluate --json` prints them (no per-score rows).
nlohmann::json libraryEvaluationJson(const library::EvaluationResult& result);
/// The results as a table for people, naming the protocol, the split and the threshold rule.
std::string libraryEvaluationText(const library::EvaluationResult& result);
/// Refuses (InputError) a report folder whose files exist, unless `force`.
void checkLibraryReportFolder(const std::filesystem::path& out, bool force);
/// Writes the report folder; each file atomically.
void writeLibraryEvaluationReport(const library::EvaluationResult& result, const std::filesystem::path& out);

}  // namespace hattr::report
