// hattr.Library: the profile library (docs/library.md) over the ops:: calls the CLI makes, its
// results as records (dicts), as `hattr library ... --json` prints them.

#include <filesystem>

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.hpp"
#include "hattr/core/error.hpp"
#include "hattr/ops/library.hpp"
#include "hattr/report/library_report.hpp"

namespace hattr::python {
namespace {

/// A library by its location (an SQLite file or a postgresql:// address); each call opens it.
struct Library {
  std::string location;
};

library::FeatureOptions featureOptions(std::size_t length, double band, double timing_weight,
                                       const std::string& normalization) {
  library::FeatureOptions o{.length = length, .band_fraction = band,
                            .normalization = analysis::parseNormalization(normalization),
                            .timing_weight = timing_weight};
  library::checkFeatureOptions(o);
  return o;
}

const library::FeatureOptions kDefaults{};

/// Opening, adding, listing and removing entries.
void bindLibraryEntries(py::class_<Library>& lib) {
  lib.def(py::init([](const std::string& location, bool create) {
            if (create) ops::libraryInit(location);
            (void)library::ProfileLibrary::open(location, !create);  // refuses what is not a library
            return Library{location};
          }),
          py::arg("location"), py::kw_only(), py::arg("create") = false,
          "Opens the library at `location` (an SQLite file or a postgresql:// address); create=True makes a new "
          "one (refused if it exists).");
  lib.def_property_readonly("location", [](const Library& l) { return l.location; }, "Where the library is.");
  lib.def(
      "import_svc2004",
      [](const Library& l, const std::filesystem::path& folder) {
        return toPython(ops::libraryImportSvc2004(l.location, folder, io::svc2004Calibration()).toJson());
      },
      py::arg("folder"),
      "Imports every signature of an SVC2004 Task 2 folder, labelled by writer, session and forgery, all or none: "
      "{library, count, keys}.");
  lib.def(
      "add",
      [](const Library& l, const HapticProfile& profile, const std::string& key, const std::string& person,
         const std::string& skill, const std::string& session, const std::string& date,
         const std::string& authenticity, const std::string& imitator, const std::string& mode) {
        const library::EntryLabels labels{.key = key, .person = person, .skill = skill, .session = session,
                                          .date = date, .device = profile.metadata().device,
                                          .source = profile.metadata().source.empty() ? "python" : profile.metadata().source,
                                          .authenticity = library::parseAuthenticity(authenticity, "authenticity"),
                                          .imitator = imitator, .mode = mode};
        library::ProfileLibrary::open(l.location).add(labels, profile);
        return key;
      },
      py::arg("profile"), py::kw_only(), py::arg("key"), py::arg("person"), py::arg("skill"), py::arg("session") = "",
      py::arg("date") = "", py::arg("authenticity") = "genuine", py::arg("imitator") = "", py::arg("mode") = "",
      "Adds a profile with its labels (a key already in the library is refused, nothing added); returns the key.");
  lib.def(
      "entries",
      [](const Library& l, const std::optional<std::string>& person, const std::optional<std::string>& skill,
         const std::optional<std::string>& session, const std::optional<std::string>& authenticity) {
        library::EntryFilter f{person, skill, session, std::nullopt};
        if (authenticity) f.authenticity = library::parseAuthenticity(*authenticity, "authenticity");
        py::list out;
        for (const auto& e : library::ProfileLibrary::open(l.location, true).list(f)) {
          out.append(toPython(ops::libraryEntryJson(e)));
        }
        return out;
      },
      py::kw_only(), py::arg("person") = py::none(), py::arg("skill") = py::none(), py::arg("session") = py::none(),
      py::arg("authenticity") = py::none(),
      "The entries the filters match, as records (key, person, skill, session, date, authenticity, samples, ...).");
  lib.def(
      "profile", [](const Library& l, const std::string& key) { return library::ProfileLibrary::open(l.location, true).profile(key); },
      py::arg("key"), "An entry's profile, sample for sample as it was added.");
  lib.def(
      "remove",
      [](const Library& l, const std::vector<std::string>& keys) { (void)ops::libraryRemove(l.location, keys); },
      py::arg("keys"), "Removes entries by key, all or none.");
}

/// Verification, identification, the evaluation.
void bindLibraryMatching(py::class_<Library>& lib) {
  lib.def(
      "verify",
      [](const Library& l, const HapticProfile& profile, const std::string& claim, const std::string& skill,
         const std::string& features, std::optional<double> threshold, const std::optional<std::string>& session,
         std::size_t length, double band, double timing_weight, const std::string& normalization, const std::string& rule) {
        const ops::VerifyOptions o{claim, skill, session, library::parseFeatureSet(features),
                                   featureOptions(length, band, timing_weight, normalization),
                                   library::parseScoreRule(rule), threshold};
        return toPython(ops::libraryVerify(l.location, profile, o).toJson());
      },
      py::arg("profile"), py::kw_only(), py::arg("claim"), py::arg("skill"), py::arg("features") = "shape+force",
      py::arg("threshold") = py::none(), py::arg("session") = py::none(), py::arg("length") = kDefaults.length,
      py::arg("band") = kDefaults.band_fraction, py::arg("timing_weight") = kDefaults.timing_weight,
      py::arg("normalization") = "paper", py::arg("rule") = "mean",
      "Verification as `hattr library verify --json`: {claim, skill, features, references, spread, score, threshold, "
      "threshold_from, accepted}. Without a threshold, the one an evaluation saved.");
  lib.def(
      "identify",
      [](const Library& l, const HapticProfile& profile, const std::string& skill, std::size_t top,
         const std::string& features, bool brute_force, std::size_t length, double band, double timing_weight,
         const std::string& normalization) {
        const ops::IdentifyOptions o{skill, library::parseFeatureSet(features),
                                     featureOptions(length, band, timing_weight, normalization), top, brute_force};
        return toPython(ops::libraryIdentify(l.location, profile, o).toJson());
      },
      py::arg("profile"), py::kw_only(), py::arg("skill"), py::arg("top") = 5, py::arg("features") = "shape+force",
      py::arg("brute_force") = false, py::arg("length") = kDefaults.length, py::arg("band") = kDefaults.band_fraction,
      py::arg("timing_weight") = kDefaults.timing_weight, py::arg("normalization") = "paper",
      "Identification as `hattr library identify --json`: {features, ranked: [{rank, person, nearest, distance}], "
      "search}, exactly (brute_force=True computes every distance: the same answer).");
  lib.def(
      "evaluate",
      [](const Library& l, std::uint64_t seed, int runs, unsigned threads, bool save_thresholds,
         const std::optional<std::filesystem::path>& out) {
        library::ProtocolOptions o;
        o.seed = seed;
        o.runs = runs;
        o.threads = threads;
        if (out) report::checkLibraryReportFolder(*out, false);
        library::EvaluationResult result;
        {
          py::gil_scoped_release unlocked;
          result = ops::libraryEvaluate(l.location, o, save_thresholds);
        }
        if (out) report::writeLibraryEvaluationReport(result, *out);
        py::dict d = toPython(report::libraryEvaluationJson(result));
        py::list scores;
        for (const auto& s : result.scores) {
          scores.append(py::dict(py::arg("split") = s.split, py::arg("features") = s.set, py::arg("claimed") = s.person,
                                 py::arg("run") = s.run, py::arg("query") = s.query, py::arg("kind") = s.kind,
                                 py::arg("score") = s.score));
        }
        d["scores"] = scores;
        return d;
      },
      py::kw_only(), py::arg("seed") = 2004, py::arg("runs") = 10, py::arg("threads") = 2,
      py::arg("save_thresholds") = false, py::arg("out") = py::none(),
      "The SVC2004 protocol as `hattr library evaluate --json`, with every score as records under 'scores'; `out` "
      "writes the report folder. Releases the GIL.");
}

}  // namespace

void bindLibrary(py::module_& m) {
  py::class_<Library> lib(m, "Library",
                          "A profile library: haptic profiles labelled by person, skill, session and authenticity, "
                          "on SQLite or PostgreSQL (docs/library.md).");
  bindLibraryEntries(lib);
  bindLibraryMatching(lib);
}

}  // namespace hattr::python
