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
#include "support/test_support.hpp"
#include "hattr/io/table_csv.hpp"

namespace hattr::analysis {
namespace {

using ::testing::HasSubstr;

using test::kNaN;

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

// SlopeWithoutMargin: y ~ x + x:a + (1 | g) (REML)
const LmmReference kSlopeWithoutMargin{"conventions", "y ~ x + x:a + (1 | g)", true,
  /*criterion*/ 195.48979043908864, /*sigma*/ 1.0871297795414525, /*aic*/ 207.48979043908864, /*bic*/ 220.05585781242124,
  {
    {"(Intercept)", 3.3398920762891353, 0.48474056542374938, 11.07701999048099, 2.5298072288679973e-05},
    {"x", 0.56963966692938428, 0.13911734310904419, 52.799468864768329, 0.00014573346508530105},
    {"x:aB", 0.69634510732998589, 0.14508533206438198, 51.377387182788574, 1.411638024915332e-05},
    {"x:aC", -0.26169999738562288, 0.12801028349031218, 51.453716669527857, 0.046050184759140564},
  },
  {
    {"x", 1, 52.799468864768329, 16.766325683113703, 0.00014573346508530105},
    {"x:a", 2, 51.525747222643133, 21.186983749741607, 1.9282586395201507e-07},
  },
  {
    {"g", "(Intercept)", "", 0.89737736384867106},
    {"Residual", "", "", 1.0871297795414525},
  },
  /*singular*/ false};

// NestedFactor: y ~ a + a:b + (1 | g) (REML)
const LmmReference kNestedFactor{"conventions", "y ~ a + a:b + (1 | g)", true,
  /*criterion*/ 185.89025696832849, /*sigma*/ 1.0651659635989714, /*aic*/ 201.89025696832849, /*bic*/ 218.6450134661053,
  {
    {"(Intercept)", 3.8105923747884782, 0.55499342534781682, 10.268952984023594, 3.82917775791984e-05},
    {"aB", 1.6982999999999919, 0.47635670038527345, 48.986868782426463, 0.00082317610672381523},
    {"aC", -0.49586611115307117, 0.48083842045982778, 49.171145645486675, 0.30746805332422189},
    {"aA:bq", 1.7714338888469305, 0.48083842045982778, 49.171145645909618, 0.00057152534845331224},
    {"aB:bq", 0.97608898678767642, 0.4808384204598275, 49.171145650170551, 0.04778774362600343},
    {"aC:bq", 1.1026550979407383, 0.48083842045982766, 49.171145649127496, 0.026151358435084891},
  },
  {
    {"a", 2, 49.109039006333667, 11.539544132292974, 7.796906551363221e-05},
    {"a:b", 3, 49.16851330361046, 7.6289064691726587, 0.00027672362682012129},
  },
  {
    {"g", "(Intercept)", "", 1.0764661322555675},
    {"Residual", "", "", 1.0651659635989714},
  },
  /*singular*/ false};

// NoIntercept: y ~ 0 + a + b + (1 | g) (REML)
const LmmReference kNoIntercept{"conventions", "y ~ 0 + a + b + (1 | g)", true,
  /*criterion*/ 189.30255923259452, /*sigma*/ 1.0587230516734381, /*aic*/ 201.30255923259452, /*bic*/ 213.86862660592712,
  {
    {"aA", 4.050471861874013, 0.52718727459428216, 7.8724991246828218, 6.3605391575084015e-05},
    {"aB", 5.3574336610298872, 0.52650947693550754, 7.8381151119904588, 8.6405035754251915e-06},
    {"aC", 3.2222460669480233, 0.52584323612017381, 7.8043130201361794, 0.00031025636793144352},
    {"bq", 1.2860989400986862, 0.27679122945653739, 51.234884342529639, 2.3952463308728388e-05},
  },
  {
    {"a", 3, 12.064096328203473, 38.266432987949287, 1.931963664896588e-06},
    {"b", 1, 51.234884342529639, 21.589575896067636, 2.3952463308728388e-05},
  },
  {
    {"g", "(Intercept)", "", 1.1000064862915166},
    {"Residual", "", "", 1.0587230516734381},
  },
  /*singular*/ false};

// NoInterceptSlopes: y ~ 0 + x + x:a + (1 | g) (REML)
const LmmReference kNoInterceptSlopes{"conventions", "y ~ 0 + x + x:a + (1 | g)", true,
  /*criterion*/ 211.64226586608527, /*sigma*/ 1.0896049771034459, /*aic*/ 221.64226586608527, /*bic*/ 232.11398867719578,
  {
    {"x", 0.35921722312586613, 0.13897680984720973, 53.631991166976768, 0.012500370650655972},
    {"x:aA", 0.26640771166076999, 0.12853983231259153, 50.611649735665615, 0.043324274127623866},
    {"x:aB", 0.9786321218750943, 0.14977235022237101, 50.825754821367198, 3.0046416429892968e-08},
  },
  {
    {"x", 1, 53.631991166976768, 6.680817768790817, 0.012500370650655972},
    {"x:a", 2, 50.725527648025952, 21.914329855521739, 1.3820831520837751e-07},
  },
  {
    {"g", "(Intercept)", "", 3.3188874752291748},
    {"Residual", "", "", 1.0896049771034459},
  },
  /*singular*/ false};

// Margins: y ~ x:a + x:b + (1 | g) (REML)
const LmmReference kMargins{"conventions", "y ~ x:a + x:b + (1 | g)", true,
  /*criterion*/ 184.947929846054, /*sigma*/ 0.96180693151220542, /*aic*/ 198.947929846054, /*bic*/ 213.60834178160869,
  {
    {"(Intercept)", 3.3999499380483504, 0.47259324882370146, 9.5166835507430498, 3.8260289552395783e-05},
    {"x:aA", 0.37336435862497452, 0.13325381158885449, 51.468000622925473, 0.007142432537007878},
    {"x:aB", 1.0303453124379658, 0.16594167242494368, 51.610410555172152, 9.2323394962896214e-08},
    {"x:aC", 0.059799887476864905, 0.13936870472420065, 51.162007959266113, 0.66966872525231991},
    {"x:bq", 0.38370144849828131, 0.099086797619351852, 50.310448901793229, 0.00031192262019128007},
  },
  {
    {"x:a", 3, 50.76366376979864, 24.25062894842533, 7.0807395993429154e-10},
    {"x:b", 1, 50.310448901793229, 14.995304598817194, 0.00031192262019128007},
  },
  {
    {"g", "(Intercept)", "", 0.92922939681367145},
    {"Residual", "", "", 0.96180693151220542},
  },
  /*singular*/ false};

// FixedOrder: y ~ (1 + x | g) + a * x (REML)
const LmmReference kFixedOrder{"conventions", "y ~ (1 + x | g) + a * x", true,
  /*criterion*/ 182.07221192797979, /*sigma*/ 0.98793141166955434, /*aic*/ 202.07221192797979, /*bic*/ 223.01565755020079,
  {
    {"(Intercept)", 3.1983953954288986, 0.67352568626787357, 13.945004130108776, 0.00031450875965745848},
    {"aB", 1.3167789550267086, 0.71080156908363878, 49.050951745396461, 0.069972150373847866},
    {"aC", -0.99027886870809056, 0.74162061862031414, 48.215472712798302, 0.18805147833498798},
    {"x", 0.6131516169978608, 0.19781441590745288, 49.113748264703148, 0.0032041335395817431},
    {"aB:x", 0.17654642433215947, 0.28829292847890681, 49.812089623015623, 0.54306828005143637},
    {"aC:x", 0.072689187772682406, 0.27443445268009226, 49.813899355240494, 0.79220329853321114},
  },
  {
    {"a", 2, 48.83909460092277, 6.2051063560746291, 0.0039695251551473392},
    {"x", 1, 47.266739241292825, 35.244412327512492, 3.2936767767598627e-07},
    {"a:x", 2, 49.801109121366643, 0.18902047827967455, 0.8283606433832218},
  },
  {
    {"g", "(Intercept)", "", 0.97271225213148027},
    {"g", "x", "", 0.013864725150055232},
    {"g", "(Intercept)", "x", -0.99999999999985845},
    {"Residual", "", "", 0.98793141166955434},
  },
  /*singular*/ true};

// GroupOrder: y ~ x + (1 + x || g) + (1 | h) (REML)
const LmmReference kGroupOrder{"conventions", "y ~ x + (1 + x || g) + (1 | h)", true,
  /*criterion*/ 209.74943901565419, /*sigma*/ 1.0543086866714273, /*aic*/ 221.74943901565419, /*bic*/ 234.31550638898679,
  {
    {"(Intercept)", 3.4464080550547771, 0.55061859727518292, 17.846332399649629, 6.9234419379358592e-06},
    {"x", 0.62547440860171188, 0.13708968612208211, 48.101384740177245, 3.501576417719856e-05},
  },
  {
    {"x", 1, 48.101384740177245, 20.816587011519125, 3.501576417719856e-05},
  },
  {
    {"h", "(Intercept)", "", 0.98215221189115032},
    {"g", "x", "", 2.0358513691994095e-08},
    {"g.1", "(Intercept)", "", 0.86702446899742824},
    {"Residual", "", "", 1.0543086866714273},
  },
  /*singular*/ true};

// CovariateAndGroup: y ~ s + (1 | s) + (1 | h) (REML)
const LmmReference kCovariateAndGroup{"conventions", "y ~ s + (1 | s) + (1 | h)", true,
  /*criterion*/ 225.62564482841043, /*sigma*/ 1.3896095705325779, /*aic*/ 235.62564482841043, /*bic*/ 246.09736763952094,
  {
    {"(Intercept)", 4.1722898699093385, 1.1034099436957594, 3.6517999739975724, 0.022893908614953225},
    {"s", 0.19451718002590515, 0.2815581101328119, 3.5414317548052705, 0.53224379501379937},
  },
  {
    {"s", 1, 3.5414317548052705, 0.47728726507753494, 0.53224379501379937},
  },
  {
    {"h", "(Intercept)", "", 0.53833907164080352},
    {"s", "(Intercept)", "", 1.081362897117206},
    {"Residual", "", "", 1.3896095705325779},
  },
  /*singular*/ false};

// MinusOne: y ~ -1 + x + b + (x - 1 | g) (REML)
const LmmReference kMinusOne{"conventions", "y ~ -1 + x + b + (x - 1 | g)", true,
  /*criterion*/ 216.28079548389707, /*sigma*/ 1.3727798013214381, /*aic*/ 226.28079548389707, /*bic*/ 236.75251829500758,
  {
    {"x", 0.51004722459707386, 0.1982006500117256, 15.275617229368329, 0.020965791252438117},
    {"bp", 3.1242230028783546, 0.40791231589407206, 52.530166880919943, 4.1506741461110006e-10},
    {"bq", 4.208552988241216, 0.43244099187159057, 53.408833834309924, 1.9889898132835008e-13},
  },
  {
    {"x", 1, 15.275617229368329, 6.6223271037928031, 0.020965791252438117},
    {"b", 2, 52.823780111980447, 49.143022416138166, 8.7890808555993768e-13},
  },
  {
    {"g", "x", "", 0.31077249154208453},
    {"Residual", "", "", 1.3727798013214381},
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

// R's conventions beyond the common formula (a review found each of these wrong once): type III
// tests of terms without their margins, no intercept, interactions named in the fixed part's
// order, lme4's order of groupings, a column both covariate and grouping, "- 1" inside terms.
TEST(Lmm, TermsWithoutTheirMarginsAreTestedAsLmerTest) {
  expectEqualsR(kSlopeWithoutMargin);
  expectEqualsR(kNestedFactor);
  expectEqualsR(kMargins);
}
TEST(Lmm, ModelsWithoutAnInterceptAreCodedAsR) {
  expectEqualsR(kNoIntercept);
  expectEqualsR(kNoInterceptSlopes);
  expectEqualsR(kMinusOne);
}
TEST(Lmm, InteractionsAreNamedInTheFixedPartsOrder) { expectEqualsR(kFixedOrder); }
TEST(Lmm, GroupingsAreOrderedAsLme4OrdersThem) { expectEqualsR(kGroupOrder); }
TEST(Lmm, AColumnCanBeACovariateAndAGrouping) { expectEqualsR(kCovariateAndGroup); }

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

TEST(Lmm, NumbersAsAFactorAreLevelsAsRWritesThem) {
  const DataTable t{{{"y", {}, {1, 2, 3, 4.5, 5, 6, 7, 8.5}},
                     {"g", {"a", "a", "b", "b", "c", "c", "d", "d"}, {}},
                     {"dose", {"01", "1", "2.50", "2.5", "1e5", "100000", "0.5", "1"}, {}}},
                    "t"};
  const LmmFit fit = fitLmm(t, "y ~ dose + (1 | g)", {.factors = {"dose"}, .tests = false});
  ASSERT_EQ(fit.fixed.size(), 4u);  // levels 0.5 (the baseline), 1, 2.5, 1e+05: "01" is 1
  EXPECT_EQ(fit.fixed[1].name, "dose1");
  EXPECT_EQ(fit.fixed[2].name, "dose2.5");
  EXPECT_EQ(fit.fixed[3].name, "dose1e+05");
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

  // lme4's own refusals: deeper nesting than a/b (write it out), a grouping of one level, as
  // many random effects as observations, a factor of one level in a random term.
  EXPECT_THAT(errorOf(data, "cost ~ mode + (1 | subject/mode/trial)"), HasSubstr("nest one level with '/'"));
  DataTable single = data;
  for (std::string& s : single.columns[0].text) s = "s01";
  EXPECT_THAT(errorOf(single, "cost ~ mode + (1 | subject)"), HasSubstr("grouping factor 'subject' has one level"));
  EXPECT_THAT(errorOf(data, "cost ~ 1 + (0 + mode | subject:trial)"), HasSubstr("random effects"));
  EXPECT_THAT(errorOf(one, "cost ~ 1 + (1 + mode | subject)"), HasSubstr("a factor in the random effects needs at least 2"));
  // A factor column whose cells read as non-finite numbers is still a factor.
  DataTable names = data;
  names.columns[1].text[0] = "inf";
  EXPECT_NO_THROW((void)fitLmm(names, "cost ~ mode + (1 | subject)", {.tests = false}));

  DataTable numbers{{{"y", {}, {1.0, 2.0, std::nan("")}}, {"g", {"a", "b", "a"}, {}}}, "numbers"};
  EXPECT_THAT(errorOf(numbers, "y ~ 1 + (1 | g)"), HasSubstr("row 3 of column 'y' is nan"));
}

}  // namespace
}  // namespace hattr::analysis
