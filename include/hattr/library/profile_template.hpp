#pragma once
/// A person's template for a skill: the average of several recordings by DTW barycenter
/// averaging (DBA, Petitjean, Ketterlin and Gançarski 2011), with the spread of the recordings
/// along it, usable as a reference wherever one is asked for (`library:PATH#PERSON/SKILL`).
///
/// hattr's reading (docs/library.md): the recordings as they are (no resampling, which would
/// draw ink across a lift); the alignment channels (shape x, y, and with force |f|), each scaled
/// by its standard deviation over all recordings, set a common DTW path (dependent DTW, absolute
/// cost, banded); the average starts at the medoid (least summed DTW cost to the others) and has
/// its length; each iteration replaces every average point by the mean of the recordings'
/// samples aligned to it (every stored field: position, force, pressure, tilt; pen down by
/// majority), until no point moves by more than 1 µm or 30 iterations. Its times are the
/// medoid's, scaled to the recordings' mean duration; its velocities are the finite
/// differences of its positions within each pen-down run. The spread at a point is the
/// RMS distance in the paper plane of the samples aligned to it [m], and their force's RMS
/// deviation [N]. Not for the servo thread.

#include <string>
#include <string_view>
#include <vector>

#include "hattr/core/haptic_profile.hpp"

namespace hattr::library {

struct TemplateOptions {
  bool align_force = true;   ///< align on the force profile as well as the shape
  int max_iterations = 30;
  double band_fraction = 0.1;  ///< DTW band of the alignments (fraction of the length)
};

struct ProfileTemplate {
  HapticProfile profile;                ///< the average, a reference like any profile
  std::vector<double> spread_m;         ///< per sample of `profile`
  std::vector<double> force_spread_N;   ///< per sample of `profile`
  int iterations = 0;
  std::size_t recordings = 0;
};

/// The template of `recordings` (at least 2, each with at least 2 samples). `metadata` names it
/// (its source is set to "library-template" with the count). Throws InputError naming what is
/// wrong.
ProfileTemplate buildTemplate(const std::vector<HapticProfile>& recordings, ProfileMetadata metadata,
                              const TemplateOptions& options = {});

/// Whether `text` names a library template ("library:PATH#PERSON/SKILL").
bool isLibraryReference(std::string_view text);
/// The template `library:PATH#PERSON/SKILL` names: built from every genuine entry of the person
/// and skill in the library at PATH. Throws InputError for a malformed reference, a missing
/// library, an unknown person or skill, or fewer than 2 recordings.
ProfileTemplate libraryTemplate(std::string_view reference, const TemplateOptions& options = {});
/// A reference as `--reference` takes it: a library template (library:PATH#PERSON/SKILL), else a
/// profile CSV file.
HapticProfile readReference(const std::string& text);

}  // namespace hattr::library
