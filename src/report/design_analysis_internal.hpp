#pragma once
// What the design analysis's files share (design_analysis.cpp, design_models.cpp): the model and
// curve fits that analyzeDesign runs on its tables. Costs are the DTW costs of analysis::TrialScore
// (normalized units). Offline code.

#include "hattr/report/design_analysis.hpp"

namespace hattr::report::detail {

/// Each phase's conditions compared by a linear mixed model of its trials (DesignAnalysis::models,
/// per phase and metric; none below two subjects). A model the data cannot take is kept with
/// PhaseModel::skipped saying why. Reads a.scores, a.phases, a.conditions, a.condition_kind.
void fitPhaseModels(DesignAnalysis& a);

/// Both laws of practice fitted to each condition's learning curve per phase and, with two
/// subjects or more, to each subject's (DesignAnalysis::fits). Reads a.curves and a.scores.
void fitCurves(DesignAnalysis& a);

}  // namespace hattr::report::detail
