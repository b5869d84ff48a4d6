#pragma once
/// Where a library's profiles come from, with their labels: a folder of SVC2004 signatures, the
/// completed trials of a study. Each returns every entry or throws before anything is stored
/// (ProfileLibrary::add then adds them all or none). Not for the servo thread.

#include <filesystem>
#include <utility>
#include <vector>

#include "hattr/io/tablet_import.hpp"
#include "hattr/library/profile_library.hpp"
#include "hattr/session/study_database.hpp"

namespace hattr::library {

using LabelledProfiles = std::vector<std::pair<EntryLabels, HapticProfile>>;

/// The SVC2004 Task 2 folder: every U<writer>S<signature>.TXT, labelled person "U<writer>", skill
/// "signature", key "svc2004/U<w>S<s>"; signatures 1–10 genuine of session "1", 11–20 genuine of
/// session "2" (about a week later), 21–40 imitations (skilled forgeries by unnamed forgers, no
/// session). Other files are ignored. Throws InputError for a folder that does not exist, holds
/// no such file or a signature number outside 1–40, and for any file that does not import.
LabelledProfiles readSvc2004Folder(const std::filesystem::path& folder, const io::TabletCalibration& calibration);

/// The completed trials of a study (those with samples): person = subject, skill = the block's,
/// session "<n>" (the schedule's, from 1), mode = the block's strategy, genuine, key
/// "study/<study name>/trial-<id>", source "study <file> trial <id>".
LabelledProfiles readStudyTrials(const session::StudyDatabase& study);

}  // namespace hattr::library
