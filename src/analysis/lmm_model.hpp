#pragma once
// The parts of a linear mixed model between its formula and its fit (lmm.hpp): the parsed
// formula, the variables, the fixed-effects matrix X, the random-effects matrix Z with the
// template of Λ(θ), and the profiled deviance. Internal to the analysis module.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include "hattr/analysis/lmm.hpp"

namespace hattr::analysis::lmm {

/// A term: a set of variables (indices into ParsedFormula::variables, ascending).
using Term = std::vector<int>;

/// "(lhs | group)": the effects `lhs` vary between the levels of the grouping factor.
struct RandomTerm {
  bool intercept = true;
  std::vector<Term> terms;  ///< the effects beside the intercept
  /// The grouping variables, an interaction when more than one, in lme4's naming order
  /// ("b:a" for a/b).
  Term group;
};

struct ParsedFormula {
  std::string text;
  std::string response;
  std::vector<std::string> variables;  ///< every variable beside the response, first use first
  bool intercept = true;
  std::vector<Term> fixed;  ///< ordered by degree, then by first appearance (R's order)
  std::vector<RandomTerm> random;
};

/// Parses an lme4 formula. Throws InputError naming the position and what was expected.
[[nodiscard]] ParsedFormula parseFormula(std::string_view text);

/// A term's label as R writes it: "mode:trial".
[[nodiscard]] std::string termLabel(const ParsedFormula& formula, const Term& term);

/// A variable of the model: numbers, or a factor's level codes with its levels.
struct Variable {
  std::string name;
  bool factor = false;
  std::vector<double> values;       ///< numeric: one per row
  std::vector<int> codes;           ///< factor: index into levels, one per row
  std::vector<std::string> levels;  ///< factor: baseline first, then sorted
};

/// Columns of a design matrix with R's names and the term each column codes
/// (-1 for the intercept).
struct Design {
  Eigen::MatrixXd matrix;
  std::vector<std::string> names;
  std::vector<int> term_of_column;
};

/// R's terms() "factors" codes (its TermCode): for each variable of each term, 1 (coded by
/// contrasts) when the term without it is empty or contained in an earlier term, else 2
/// (coded by one indicator a level). Terms in the model's order.
[[nodiscard]] std::vector<std::vector<int>> termCodes(const std::vector<Term>& terms);

/// R's model.matrix(): the intercept, then each term's columns, a factor coded by treatment
/// contrasts or indicators as termCodes() says, except that without an intercept the first
/// factor of the first term that has one takes indicators. `full_indicators` codes every
/// factor by indicators (lmerTest's rank-deficient matrix for type III hypotheses).
[[nodiscard]] Design designMatrix(const std::vector<Variable>& variables, bool intercept,
                                  const std::vector<Term>& terms, bool full_indicators = false);

/// One random-effects term, ready to fit.
struct RandomBlock {
  std::string group_name;
  std::vector<std::string> effects;  ///< the columns of its model matrix: "(Intercept)", "trial"
  std::vector<int> group_of_row;     ///< level index of the grouping factor, one per row
  std::size_t levels = 0;
  Eigen::MatrixXd effects_matrix;  ///< rows × effects
  std::size_t theta_offset = 0;     ///< its first element in θ
  [[nodiscard]] std::size_t size() const { return effects.size(); }
};

/// Everything the deviance needs.
struct Model {
  ParsedFormula formula;
  Eigen::VectorXd y;
  Design fixed;  ///< X, after dependent columns are dropped
  std::vector<std::string> dropped;
  std::vector<RandomBlock> blocks;  ///< ordered by decreasing number of levels (lme4's order)
  std::vector<Variable> variables;
  std::size_t theta_size = 0;
  std::vector<double> theta_lower;  ///< 0 for a diagonal element of Λ, -inf otherwise
};

/// Builds the model from the data. Throws InputError for unknown columns, missing or
/// non-finite values, a factor with one level, or a grouping factor with as many levels as rows.
[[nodiscard]] Model buildModel(const DataTable& data, const ParsedFormula& formula, const LmmOptions& options);

/// The profiled deviance of a model and the solution at the last θ it was evaluated at.
class Deviance {
 public:
  /// The dense Schur complement is used while the random effects beyond the first block
  /// number at most `dense_schur_limit` and, times the first block's, its square; 0 takes
  /// the sparse path always (the tests compare the two).
  Deviance(const Model& model, bool reml, Eigen::Index dense_schur_limit = 1500);
  /// The profiled REML criterion or ML deviance at θ (σ profiled out).
  double operator()(const Eigen::VectorXd& theta);
  /// The criterion at θ and a given σ (lmerTest's devfun_vp), for the Satterthwaite Hessian.
  double atSigma(const Eigen::VectorXd& theta, double sigma);
  /// σ² (X'V⁻¹X)⁻¹ at θ: the covariance of β̂ (lmerTest's get_covbeta).
  Eigen::MatrixXd covarianceOfBeta(const Eigen::VectorXd& theta, double sigma);

  // The solution at the last θ evaluated.
  [[nodiscard]] const Eigen::VectorXd& beta() const { return beta_; }
  [[nodiscard]] double pwrss() const { return pwrss_; }
  [[nodiscard]] double sigmaHat() const;  ///< σ̂: √(pwrss / n) (ML) or √(pwrss / (n - p)) (REML)
  [[nodiscard]] std::size_t evaluations() const { return evaluations_; }

 private:
  void solve(const Eigen::VectorXd& theta);
  void setLambda(const Eigen::VectorXd& theta);
  static Eigen::SparseMatrix<double> lowerWithDiagonal(const Eigen::SparseMatrix<double>& m);
  void factorA();
  [[nodiscard]] Eigen::MatrixXd solveA(const Eigen::MatrixXd& b) const;
  [[nodiscard]] Eigen::MatrixXd solveFirstBlock(const Eigen::MatrixXd& b) const;

  const Model& model_;
  bool reml_;
  Eigen::SparseMatrix<double> zt_;   // Zᵀ, q × n
  Eigen::SparseMatrix<double> z_;
  Eigen::SparseMatrix<double> ztz_;  // ZᵀZ
  Eigen::MatrixXd ztx_;
  Eigen::VectorXd zty_;
  Eigen::MatrixXd xtx_;
  Eigen::VectorXd xty_;
  Eigen::SparseMatrix<double> lambda_;  // Λ(θ), its values mapped from θ by lambda_index_
  std::vector<int> lambda_index_;
  // ΛᵀZᵀZΛ + I in a fixed pattern, and for a diagonal Λ each value's two θ indices.
  Eigen::SparseMatrix<double> a_;
  Eigen::SparseMatrix<double> ztz_lower_;
  bool diagonal_lambda_ = false;
  std::vector<std::pair<int, int>> a_theta_;
  // Natural order: the blocks come sorted by decreasing number of levels, which keeps the
  // fill of crossed designs in the smaller factor's block (lme4's reason for that order).
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::NaturalOrdering<int>> cholesky_;
  // The block path: the first block's factors side by side, C = A₂₁, W = A₁₁⁻¹Cᵀ, S₂'s factor.
  bool block_path_ = false;
  Eigen::Index first_block_size_ = 0;
  Eigen::Index first_block_columns_ = 0;
  Eigen::MatrixXd block_factors_;
  Eigen::MatrixXd c_;
  Eigen::MatrixXd w_;
  Eigen::LLT<Eigen::MatrixXd> schur_a_;
  Eigen::MatrixXd schur_;  // R_XᵀR_X = X'X − ...: (X'V⁻¹X) / σ²
  Eigen::VectorXd beta_;
  double pwrss_ = 0.0;
  double log_det_l_ = 0.0;
  double log_det_rx_ = 0.0;
  std::size_t evaluations_ = 0;
};

/// Minimizes f over x ≥ lower (elementwise) by Nelder-Mead, restarted from the best point
/// until a restart no longer improves. Returns the minimizer.
struct Minimum {
  Eigen::VectorXd x;
  double value = 0.0;
  bool converged = false;
};
template <class F>
Minimum minimizeNelderMead(F&& f, Eigen::VectorXd start, const std::vector<double>& lower);

// Inference (lmm_inference.cpp).

/// Satterthwaite's machinery of lmerTest: the covariance of β̂, the asymptotic covariance of
/// the variance parameters (θ, σ) and the Jacobian of the former in the latter.
struct Satterthwaite {
  Eigen::MatrixXd vcov_beta;
  Eigen::MatrixXd vcov_varpar;
  std::vector<Eigen::MatrixXd> jacobian;  ///< one p × p matrix per variance parameter
  std::vector<std::string> warnings;
};
[[nodiscard]] Satterthwaite satterthwaite(Deviance& deviance, const Eigen::VectorXd& theta, double sigma);

/// The t test of the contrast Lβ (lmerTest's contest1D): fills std_error, df, t, p.
void testContrast(const Satterthwaite& s, const Eigen::VectorXd& beta, const Eigen::RowVectorXd& l,
                  LmmCoefficient& out);
/// The F test of the hypothesis Lβ = 0 (lmerTest's contestMD).
[[nodiscard]] LmmTermTest testHypothesis(const Satterthwaite& s, const Eigen::VectorXd& beta, const Eigen::MatrixXd& l);

/// lmerTest's type III hypothesis matrices, one per fixed term (type I for a single term).
[[nodiscard]] std::vector<Eigen::MatrixXd> typeThreeHypotheses(const Model& model);

}  // namespace hattr::analysis::lmm
