#pragma once
/// Moving a study's data out of and into the database: a folder with the definition, the
/// expert references, a trials table and one profile CSV per completed trial.
///
///   OUT/study.json            the definition (experts point into experts/)
///   OUT/experts/<skill>.csv   the expert references
///   OUT/trials.csv            one row per planned trial (status, attempts, file, ...)
///   OUT/trials/<subject>/<sequence>_<mode>_<phase>_<index>.csv   every completed trial

#include <filesystem>

#include "hattr/session/study_database.hpp"

namespace hattr::session {

/// A trial's file in an export (and in a rescue folder): trials/<subject>/<sequence>_<mode>_<phase>_<index>.csv.
/// Throws InputError for a subject id that would leave the folder.
std::string trialFileName(const TrialPlan& plan);

struct ExportOptions {
  /// Keep learners' names and notes (session/learner.hpp) in study.json. Off by default: the
  /// export is pseudonymized, each learner named by their code only.
  bool identified = false;
};

/// Writes the export folder (created; refuses an existing non-empty folder). Returns the
/// number of trial profiles written.
std::size_t exportStudy(const StudyDatabase& db, const std::filesystem::path& out_dir, const ExportOptions& options = {});

/// Creates a new study database from an export folder: the definition, the experts, the
/// plan, and every completed trial's profile, exactly as exported. Returns the number of
/// trials imported. Throws InputError naming the file and line of anything malformed.
std::size_t importStudy(const std::filesystem::path& export_dir, const std::filesystem::path& db_file);

}  // namespace hattr::session
