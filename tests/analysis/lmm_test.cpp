// Linear mixed models against R: lme4 1.1.31's lmer() and lmerTest 3.1.3's summary()
// (Satterthwaite) and anova(type = 3), on R 4.2.2. Every literal below was printed by
//   cd tests/analysis && LC_ALL=C Rscript lmm_reference.R
// (the script beside this file), which also wrote the data sets in lmm_reference/: seeded
// designs with missing trials (unbalanced), random slopes, crossed and nested groupings,
// independent effects (||) and a singular fit. The tests do not need R.
//
// Agreement required (issue 37): fixed effects and standard errors to 1e-5 relative,
// degrees of freedom and p-values to 1e-4, variance components to 1e-5 relative.

#include "hattr/analysis/lmm.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "analysis/lmm_model.hpp"  // internal: the deviance's two factorizations
#include "hattr/core/error.hpp"
#include "hattr/io/table_csv.hpp"

namespace hattr::analysis {
namespace {

using ::testing::HasSubstr;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct CoefficientRow {
  const char* name;
  double estimate, std_error, df, p;
};
struct TermRow {
  const char* term;
  double num_df, den_df, f, p;
};
struct VarianceRow {
  const char* group;
  const char* effect;
  const char* other;
  double value;  // a standard deviation or a correlation
};
struct LmmReference {
  const char* data;
  const char* formula;
  bool reml;
  double criterion, sigma, aic, bic;
  std::vector<CoefficientRow> fixed;
  std::vector<TermRow> terms;
  std::vector<VarianceRow> variances;
  bool singular;
};

// Slopes: cost ~ mode * trial + (1 + trial | subject) (REML)
const LmmReference kSlopes{"slopes", "cost ~ mode * trial + (1 + trial | subject)", true,
  /*criterion*/ 899.51708898601942, /*sigma*/ 1.5814148404187698, /*aic*/ 919.51708898601942, /*bic*/ 953.72243897874228,
  {
    {"(Intercept)", 17.73633520228196, 0.51587661269860396, 24.410939373326475, 3.4088018599397764e-22},
    {"modeBASIC", 3.1278331203358753, 0.58960231800827323, 205.02301296860054, 2.9105650354472131e-07},
    {"modePCONTROL", 1.9084402083458516, 0.57290247199644406, 203.5234508865976, 0.0010269119552055554},
    {"trial", -0.72302123268242846, 0.14633426542357902, 13.748797824584257, 0.00022889736412887011},
    {"modeBASIC:trial", 0.02363738164214799, 0.11432167242129844, 204.19656117075795, 0.83640173391436012},
    {"modePCONTROL:trial", -0.071876945537978201, 0.11311664889146124, 203.19745504330515, 0.52586735569238963},
  },
  {
    {"mode", 2, 204.25891089844063, 14.455797529354179, 1.3437291794468057e-06},
    {"trial", 1, 9.0938099313687655, 31.410818062295778, 0.00032006681889302715},
    {"mode:trial", 2, 203.78970322941444, 0.37230217697834256, 0.68961371422021611},
  },
  {
    {"subject", "(Intercept)", "", 1.0174089838964178},
    {"subject", "trial", "", 0.39004853210855328},
    {"subject", "(Intercept)", "trial", 0.1587280263142791},
    {"Residual", "", "", 1.5814148404187698},
  },
  /*singular*/ false};

// SlopesMl: cost ~ mode * trial + (1 + trial | subject) (ML)
const LmmReference kSlopesMl{"slopes", "cost ~ mode * trial + (1 + trial | subject)", false,
  /*criterion*/ 889.84806040264368, /*sigma*/ 1.5659998221511544, /*aic*/ 909.84806040264368, /*bic*/ 944.05341039536654,
  {
    {"(Intercept)", 17.738801940962379, 0.49790655016822255, 28.924163535282503, 1.9039107913334912e-25},
    {"modeBASIC", 3.1281256295006465, 0.58364862946987051, 209.33227345123632, 2.193626998745415e-07},
    {"modePCONTROL", 1.9035841397670206, 0.56722581552765983, 207.66883386749512, 0.00094039654317364259},
    {"trial", -0.72336885890407643, 0.14000284793446247, 15.793243125440327, 9.7548568000396834e-05},
    {"modeBASIC:trial", 0.02354540765101451, 0.11317946226194131, 208.41438881099333, 0.83540397649294251},
    {"modePCONTROL:trial", -0.07121166454231917, 0.11200021928777647, 207.30833664675777, 0.52559685617502816},
  },
  {
    {"mode", 2, 208.48632963800637, 14.745474219400554, 1.0242493761101675e-06},
    {"trial", 1, 10.113376658209214, 34.904247303119128, 0.00014286301902927443},
    {"mode:trial", 2, 207.96559697393778, 0.37354964683642095, 0.68874768734343905},
  },
  {
    {"subject", "(Intercept)", "", 0.94074182684973484},
    {"subject", "trial", "", 0.36772739117142145},
    {"subject", "(Intercept)", "trial", 0.18678530714908001},
    {"Residual", "", "", 1.5659998221511544},
  },
  /*singular*/ false};

// Crossed: score ~ group + (1 | subject) + (1 | item) (REML)
const LmmReference kCrossed{"crossed", "score ~ group + (1 | subject) + (1 | item)", true,
  /*criterion*/ 143.88318857353846, /*sigma*/ 0.59188682103380041, /*aic*/ 155.88318857353846, /*bic*/ 168.74199693188766,
  {
    {"(Intercept)", 4.3875296967572615, 0.4152968072069978, 11.771641715448107, 2.3427815607981963e-07},
    {"groupfree", 0.65436984510547502, 0.54297987512824319, 9.1844143793157542, 0.25827944836666294},
    {"groupguided", -0.15333078364514954, 0.54410990499807488, 9.2619754162569787, 0.78429142605652435},
  },
  {
    {"group", 2, 9.1413995353293327, 1.2623898546309889, 0.32801218180916641},
  },
  {
    {"subject", "(Intercept)", "", 0.71998026282975525},
    {"item", "(Intercept)", "", 0.36976184650196514},
    {"Residual", "", "", 0.59188682103380041},
  },
  /*singular*/ false};

// Nested: speed ~ plan * hand + (1 | school/class) (REML)
const LmmReference kNested{"nested", "speed ~ plan * hand + (1 | school/class)", true,
  /*criterion*/ 541.33710522163176, /*sigma*/ 1.8989363231893763, /*aic*/ 555.33710522163176, /*bic*/ 575.19107857029212,
  {
    {"(Intercept)", 32.386388888888774, 0.87709219396511506, 4.4513995876255255, 1.0409643630736015e-06},
    {"planweekly", 1.1108333333335361, 1.2801355262776637, 5.04759027466425, 0.4248573679102185},
    {"handright", -2.6699999999999209, 0.4475835837228857, 106.15105219090506, 3.2564916962731845e-08},
    {"planweekly:handright", 0.46416666666658452, 0.70769178393249266, 106.15105220548256, 0.51331520575011635},
  },
  {
    {"plan", 1, 4.0277352651283866, 1.2323046207039512, 0.32879751525334133},
    {"hand", 1, 106.15105220249328, 47.468925028646346, 4.116667202924417e-10},
    {"plan:hand", 1, 106.15105220548256, 0.43018928705851056, 0.51331520575011635},
  },
  {
    {"class:school", "(Intercept)", "", 1.1282373773642336},
    {"school", "(Intercept)", "", 1.2582007101236707},
    {"Residual", "", "", 1.8989363231893763},
  },
  /*singular*/ false};

// Independent: cost ~ mode + trial + (1 + trial || subject) (REML)
const LmmReference kIndependent{"slopes", "cost ~ mode + trial + (1 + trial || subject)", true,
  /*criterion*/ 895.11555810003597, /*sigma*/ 1.5756506011293334, /*aic*/ 909.11555810003597, /*bic*/ 933.05930309494192,
  {
    {"(Intercept)", 17.80828784762247, 0.43223346290166981, 12.293875400195027, 1.4968555505788762e-14},
    {"modeBASIC", 3.2395157683039675, 0.25707888049399646, 206.06413441735646, 2.281428786416767e-27},
    {"modePCONTROL", 1.5866561673869137, 0.25720147312797287, 205.81940144679126, 3.5883987767366791e-09},
    {"trial", -0.738857039180843, 0.13440757750138474, 9.6074908880468914, 0.00030299277208410962},
  },
  {
    {"mode", 2, 205.86620903687088, 79.400674694107593, 2.757201828590468e-26},
    {"trial", 1, 9.6074908880468914, 30.218529251111583, 0.00030299277208410962},
  },
  {
    {"subject", "(Intercept)", "", 1.0441914871473945},
    {"subject.1", "trial", "", 0.39883831248446172},
    {"Residual", "", "", 1.5756506011293334},
  },
  /*singular*/ false};

// Singular: time ~ trial + (1 | subject) (REML)
const LmmReference kSingular{"singular", "time ~ trial + (1 | subject)", true,
  /*criterion*/ 38.618631093396857, /*sigma*/ 0.42182316877370035, /*aic*/ 46.618631093396857, /*bic*/ 52.223420620045481,
  {
    {"(Intercept)", 3.1883333333333259, 0.1806138903322565, 27.999999999845311, 1.0427626722140859e-16},
    {"trial", -0.17833333333333123, 0.054457136923499391, 27.999999999809887, 0.0028162709525204801},
  },
  {
    {"trial", 1, 27.999999999809887, 10.723966418407993, 0.0028162709525204801},
  },
  {
    {"subject", "(Intercept)", "", 0},
    {"Residual", "", "", 0.42182316877370035},
  },
  /*singular*/ true};


// EmptyCell: speed ~ plan * hand + (1 | school) (REML)
const LmmReference kEmptyCell{"empty_cell", "speed ~ plan * hand + (1 | school)", true,
  /*criterion*/ 481.0361898581458, /*sigma*/ 2.1909441646707974, /*aic*/ 491.0361898581458, /*bic*/ 504.44684599376689,
  {
    {"(Intercept)", 32.386388888888931, 0.8151039221746188, 4.4450079036719234, 7.6409417214648254e-07},
    {"planweekly", 1.5749999999998705, 1.1527310214828481, 4.4450079029728657, 0.23688748309514909},
    {"handright", -2.6699999999999662, 0.51641049201327238, 100.98821145148288, 1.1851920966815147e-06},
  },
  {
    {"plan", 1, 4.4450079029728657, 1.8668316479431206, 0.23688748309514909},
    {"hand", 1, 100.98821145148288, 26.732058820880177, 1.1851920966815147e-06},
    {"plan:hand", kNaN, kNaN, kNaN, kNaN},
  },
  {
    {"school", "(Intercept)", "", 1.2622058142162287},
    {"Residual", "", "", 2.1909441646707974},
  },
  /*singular*/ false};

constexpr double kLrtChiSq = 118.58882277791452;
constexpr double kLrtDf = 2;
constexpr double kLrtP = 1.7732269617095018e-26;

// ---- Helpers ------------------------------------------------------------------------

std::filesystem::path referenceDir() {
  const char* source = std::getenv("HATTR_SOURCE_DIR");
  return std::filesystem::path(source != nullptr ? source : ".") / "tests" / "analysis" / "lmm_reference";
}

/// A data set of lmm_reference/ as the CLI reads it: text cells.
DataTable readData(const std::string& name) {
  const io::Table t = io::readTable(referenceDir() / (name + ".csv"));
  DataTable data;
  data.source = name + ".csv";
  for (const std::string& c : t.columns) data.columns.push_back({c, t.text(c), {}});
  return data;
}

void expectRelative(double actual, double expected, double tolerance, const std::string& what) {
  if (std::isnan(expected)) {
    EXPECT_TRUE(std::isnan(actual)) << what << ": got " << actual << ", R gives NA";
    return;
  }
  EXPECT_LE(std::abs(actual - expected), tolerance * std::abs(expected))
      << what << ": got " << actual << ", R gives " << expected;
}

/// A standard deviation near zero (a singular fit) is compared absolutely.
void expectVariance(double actual, double expected, const std::string& what) {
  if (std::abs(expected) < 1e-3) {
    EXPECT_LE(std::abs(actual - expected), 1e-4) << what << ": got " << actual << ", R gives " << expected;
  } else {
    expectRelative(actual, expected, 1e-5, what);
  }
}

LmmFit fitReference(const LmmReference& r) {
  return fitLmm(readData(r.data), r.formula, {.reml = r.reml});
}

/// Every number R printed, each to the tolerance.
void expectEqualsR(const LmmReference& r) {
  SCOPED_TRACE(r.formula);
  const LmmFit fit = fitReference(r);
  expectRelative(fit.criterion, r.criterion, 1e-9, "criterion");
  expectRelative(fit.sigma, r.sigma, 1e-5, "sigma");
  expectRelative(fit.aic, r.aic, 1e-9, "AIC");
  expectRelative(fit.bic, r.bic, 1e-9, "BIC");
  EXPECT_EQ(fit.singular, r.singular);
  ASSERT_EQ(fit.fixed.size(), r.fixed.size());
  for (std::size_t i = 0; i < r.fixed.size(); ++i) {
    const LmmCoefficient& c = fit.fixed[i];
    const CoefficientRow& e = r.fixed[i];
    EXPECT_EQ(c.name, e.name);
    expectRelative(c.estimate, e.estimate, 1e-5, c.name + " estimate");
    expectRelative(c.std_error, e.std_error, 1e-5, c.name + " std. error");
    expectRelative(c.df, e.df, 1e-4, c.name + " df");
    expectRelative(c.p, e.p, 1e-4, c.name + " p");
  }
  ASSERT_EQ(fit.terms.size(), r.terms.size());
  for (std::size_t i = 0; i < r.terms.size(); ++i) {
    const LmmTermTest& t = fit.terms[i];
    const TermRow& e = r.terms[i];
    EXPECT_EQ(t.term, e.term);
    expectRelative(t.num_df, e.num_df, 0.0, t.term + " numerator df");
    expectRelative(t.den_df, e.den_df, 1e-4, t.term + " denominator df");
    expectRelative(t.f, e.f, 1e-5, t.term + " F");
    expectRelative(t.p, e.p, 1e-4, t.term + " p");
  }
  ASSERT_EQ(fit.variances.size(), r.variances.size());
  for (std::size_t i = 0; i < r.variances.size(); ++i) {
    const LmmVarianceComponent& v = fit.variances[i];
    const VarianceRow& e = r.variances[i];
    EXPECT_EQ(v.group, e.group);
    EXPECT_EQ(v.effect, e.effect);
    EXPECT_EQ(v.other, e.other);
    expectVariance(v.value, e.value, v.group + " " + v.effect + " " + v.other);
  }
}

// ---- Against R ----------------------------------------------------------------------

TEST(Lmm, RandomSlopesByRemlEqualR) { expectEqualsR(kSlopes); }
TEST(Lmm, RandomSlopesByMaximumLikelihoodEqualR) { expectEqualsR(kSlopesMl); }
TEST(Lmm, CrossedGroupingsEqualR) { expectEqualsR(kCrossed); }
TEST(Lmm, NestedGroupingsAndAFactorInteractionEqualR) { expectEqualsR(kNested); }
TEST(Lmm, IndependentEffectsEqualR) { expectEqualsR(kIndependent); }
TEST(Lmm, SingularFitEqualsRAndSaysSo) {
  expectEqualsR(kSingular);
  const LmmFit fit = fitReference(kSingular);
  ASSERT_FALSE(fit.warnings.empty());
  EXPECT_THAT(fit.warnings[0], HasSubstr("singular"));
  EXPECT_THAT(fit.warnings[0], HasSubstr("'(Intercept)' of 'subject'"));
}

TEST(Lmm, LikelihoodRatioTestEqualsLme4Anova) {
  const DataTable data = readData("slopes");
  const LmmFit smaller = fitLmm(data, "cost ~ trial + (1 + trial | subject)", {.reml = false});
  const LmmFit larger = fitLmm(data, "cost ~ mode + trial + (1 + trial | subject)", {.reml = false});
  const LikelihoodRatioTest t = likelihoodRatio(smaller, larger);
  expectRelative(t.chi_sq, kLrtChiSq, 1e-6, "chi square");
  EXPECT_EQ(static_cast<double>(t.df), kLrtDf);
  expectRelative(t.p, kLrtP, 1e-4, "p");
  // REML fits are refused: their criteria are not comparable across fixed effects.
  const LmmFit reml = fitLmm(data, "cost ~ trial + (1 + trial | subject)");
  EXPECT_THROW((void)likelihoodRatio(reml, larger), InputError);
  EXPECT_THROW((void)likelihoodRatio(larger, smaller), InputError);
}

// The deviance factors A = ΛᵀZᵀZΛ + I by a dense Schur complement of the first block while
// the rest is small (every design above) and by a sparse LDLᵀ beyond; both give one deviance.
TEST(Lmm, DenseSchurAndSparseFactorizationsAgree) {
  const std::pair<const char*, const char*> designs[] = {
      {"slopes", "cost ~ mode * trial + (1 + trial | subject)"},
      {"crossed", "score ~ group + (1 | subject) + (1 | item)"},
      {"nested", "speed ~ plan * hand + (1 + hand | school/class)"}};
  for (const auto& [name, formula] : designs) {
    const lmm::Model model = lmm::buildModel(readData(name), lmm::parseFormula(formula), {});
    lmm::Deviance dense(model, true);
    lmm::Deviance sparse(model, true, 0);
    for (double scale : {0.3, 1.0, 2.5}) {
      Eigen::VectorXd theta(static_cast<Eigen::Index>(model.theta_size));
      for (Eigen::Index i = 0; i < theta.size(); ++i) theta[i] = scale * (model.theta_lower[static_cast<std::size_t>(i)] == 0.0 ? 1.0 : 0.2);
      const double d = dense(theta);
      EXPECT_NEAR(d, sparse(theta), 1e-9 * std::abs(d)) << name << " at scale " << scale;
      EXPECT_LE((dense.beta() - sparse.beta()).cwiseAbs().maxCoeff(), 1e-9) << name;
      EXPECT_NEAR(dense.atSigma(theta, 1.3), sparse.atSigma(theta, 1.3), 1e-9 * std::abs(d)) << name;
    }
  }
}

// ---- R's conventions ----------------------------------------------------------------

TEST(Lmm, ReferenceLevelChangesTheBaselineNotTheFit) {
  const DataTable data = readData("slopes");
  const LmmFit alpha = fitLmm(data, "cost ~ mode + trial + (1 | subject)");
  const LmmFit basic = fitLmm(data, "cost ~ mode + trial + (1 | subject)", {.reference = {{"mode", "BASIC"}}});
  EXPECT_EQ(alpha.fixed[1].name, "modeBASIC");
  EXPECT_EQ(basic.fixed[1].name, "modeALPHA");
  EXPECT_EQ(basic.fixed[2].name, "modePCONTROL");
  // ALPHA − BASIC is the negative of BASIC − ALPHA; the likelihood is the same.
  EXPECT_NEAR(basic.fixed[1].estimate, -alpha.fixed[1].estimate, 1e-6);
  EXPECT_NEAR(basic.criterion, alpha.criterion, 1e-8);
  EXPECT_NEAR(basic.terms[0].f, alpha.terms[0].f, 1e-6);
}

TEST(Lmm, AnEmptyCellDropsTheDependentColumnAsLme4AndSaysSo) {
  expectEqualsR(kEmptyCell);  // R's anova() gives NA for the term it cannot test: so does hattr
  const LmmFit fit = fitReference(kEmptyCell);
  ASSERT_FALSE(fit.warnings.empty());
  EXPECT_THAT(fit.warnings.back(), HasSubstr("dropped planweekly:handright"));
}

// ---- Bad input ----------------------------------------------------------------------

std::string errorOf(const DataTable& data, const std::string& formula, const LmmOptions& options = {}) {
  try {
    (void)fitLmm(data, formula, options);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Lmm, BadInputIsRefusedWithWhatAndWhere) {
  const DataTable data = readData("slopes");
  EXPECT_THAT(errorOf(data, "cost ~ mode + (1 | sbject)"), HasSubstr("column 'sbject', which is not in the table"));
  EXPECT_THAT(errorOf(data, "cost ~ mode"), HasSubstr("no random-effects term"));
  EXPECT_THAT(errorOf(data, "cost ~ mode + (1 | subject"), HasSubstr("expected ')'"));
  EXPECT_THAT(errorOf(data, "cost mode"), HasSubstr("expected '~'"));
  EXPECT_THAT(errorOf(data, "cost ~ mode + (1 | subject)", {.reference = {{"mode", "FAST"}}}),
              HasSubstr("reference level 'FAST' of 'mode' is not in the data"));
  EXPECT_THAT(errorOf(data, "subject ~ trial + (1 | mode)"), HasSubstr("the response 'subject' is not numeric"));

  DataTable one = data;  // a factor with one level
  for (std::string& m : one.columns[1].text) m = "BASIC";
  EXPECT_THAT(errorOf(one, "cost ~ mode + (1 | subject)"), HasSubstr("factor 'mode' has one level ('BASIC')"));

  DataTable missing = data;  // a missing and a non-finite value
  missing.columns[3].text[4] = "NA";
  EXPECT_THAT(errorOf(missing, "cost ~ mode + (1 | subject)"), HasSubstr("row 5 of column 'cost' is missing"));
  missing.columns[3].text[4] = "inf";
  EXPECT_THAT(errorOf(missing, "cost ~ mode + (1 | subject)"), HasSubstr("row 5 of column 'cost' is 'inf'"));
  // ...but only in the columns the formula uses.
  DataTable unused = data;
  unused.columns.push_back({"notes", std::vector<std::string>(data.columns[0].text.size(), "NA"), {}});
  EXPECT_NO_THROW((void)fitLmm(unused, "cost ~ mode + (1 | subject)", {.tests = false}));

  DataTable numbers{{{"y", {}, {1.0, 2.0, std::nan("")}}, {"g", {"a", "b", "a"}, {}}}, "numbers"};
  EXPECT_THAT(errorOf(numbers, "y ~ 1 + (1 | g)"), HasSubstr("row 3 of column 'y' is nan"));
}

}  // namespace
}  // namespace hattr::analysis
