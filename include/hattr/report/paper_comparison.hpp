#pragma once
/// What the paper reports (Srimathveeravalli & Kesavadas, "Motor Skill Training Assistance
/// Using Haptic Attributes": section 6, its Table 1 and section 7), kept as data with the
/// place each finding comes from, and a study's analysis set beside it point by point:
/// `hattr study report` prints the comparison and the report carries it.
///
/// The paper gives significance statements, not F values, and the figures' means and
/// variances only as captions; so a point agrees when hattr reaches the same statement
/// (significant or not at α = 0.05, the same mode least or most). Offline code.

#include <string>
#include <vector>

#include "hattr/report/study_analysis.hpp"
#include "hattr/session/study.hpp"

namespace hattr::report {

/// The paper's two metrics, as hattr names them ("trajectory", "force") and as the paper does.
enum class PaperMetric { kShape, kHapticProfile };

/// A per-mode ANOVA finding of section 6: in `mode`, the factor ("trial": the effect of
/// training; "subject": the difference between subjects) was significant or not.
struct PaperAnovaFinding {
  PaperMetric metric = PaperMetric::kShape;
  std::string mode;    ///< "BASIC", "PCONTROL", "ALPHA"
  std::string factor;  ///< "trial" or "subject"
  bool significant = false;
  std::string p_text;  ///< the p bound the paper gives ("p < 0.001"), or ""
};

/// One row of the paper's Table 1.
struct PaperTable1Row {
  int person = 0;
  std::string shape;           ///< best mode, character shape match
  std::string haptic_profile;  ///< best mode, haptic profile match
};

/// Section 6, "Character Shape Match" and "Haptic Profile Shape Match" paragraphs.
const std::vector<PaperAnovaFinding>& paperAnovaFindings();
/// Section 6, Table 1 (10 subjects).
const std::vector<PaperTable1Row>& paperTable1();

/// How a point of the comparison came out.
enum class Agreement { kAgrees, kDiffers, kNotMeasured };
std::string_view agreementName(Agreement agreement);  ///< "agrees", "differs", "not measured"

/// One point: what the paper says (and where), what this study measured.
struct ComparisonRow {
  std::string point;   ///< e.g. "shape, BASIC: effect of training"
  std::string source;  ///< e.g. "section 6"
  std::string paper;
  std::string hattr;
  Agreement agreement = Agreement::kNotMeasured;
};

struct PaperComparison {
  /// False when the study does not train the paper's skill (ந, "na") in the paper's three modes
  /// (then `rows` is empty).
  bool applicable = false;
  double alpha = 0.05;  ///< significance level the points were judged at
  /// Where the study's protocol differs from the paper's (subjects, trials, what the
  /// trainee sees), each as one sentence; empty when it follows the paper.
  std::vector<std::string> protocol_differences;
  std::vector<ComparisonRow> rows;
  [[nodiscard]] int count(Agreement agreement) const;
};

/// Sets `analysis` beside the paper's findings, judging significance at `alpha`.
PaperComparison compareWithPaper(const session::StudyDefinition& study, std::size_t subject_count,
                                 const StudyAnalysis& analysis, double alpha = 0.05);

/// The comparison as JSON: applicable, alpha, protocol_differences, counts and rows.
nlohmann::json comparisonToJson(const PaperComparison& comparison);

/// The comparison as lines of plain text (a header, one block per point), for the terminal.
std::vector<std::string> comparisonText(const PaperComparison& comparison);

}  // namespace hattr::report
