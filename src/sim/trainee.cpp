#include "hattr/sim/trainee.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "random_internal.hpp"
#include "trainee_internal.hpp"

namespace hattr::sim {
namespace {

// Independent random streams derived from the trainee's seed.
constexpr std::uint64_t kDeviationStream = 0x446576696174696FULL;   // "Deviatio"
constexpr std::uint64_t kPerceptionStream = 0x5065726365707469ULL;  // "Percepti"
constexpr std::uint64_t kTrialNoiseStream = 0x547269616C4E6F69ULL;  // "TrialNoi"
constexpr std::uint64_t kPaceStream = 0x547269616C506163ULL;        // "TrialPac"

/// device::HandCommand's and device::ProfileHandScript's altitude when a profile has no tilt.
constexpr double kDefaultAltitude_rad = 1.0471975511965976;

/// Linear interpolation of a recording at times on the template's grid (both relative to their
/// first samples). `valid[i]` is false where the recording does not cover t[i].
struct Resampled {
  Eigen::MatrixX2d p_xy;
  Eigen::MatrixX3d f_guide;
  std::vector<char> pen_down;
  std::vector<char> valid;
};

Resampled resample(const HapticProfile& profile, const std::vector<double>& t) {
  const auto& s = profile.samples();
  const auto n = static_cast<Eigen::Index>(t.size());
  Resampled out{Eigen::MatrixX2d::Zero(n, 2), Eigen::MatrixX3d::Zero(n, 3), std::vector<char>(t.size(), 0),
                std::vector<char>(t.size(), 0)};
  const double t0 = s.front().t_s;
  const double end = s.back().t_s - t0;
  std::size_t j = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] > end + 1e-9) break;
    while (j + 2 < s.size() && s[j + 1].t_s - t0 <= t[i]) ++j;
    const Sample& a = s[j];
    const Sample& b = s[std::min(j + 1, s.size() - 1)];
    const double span = b.t_s - a.t_s;
    const double w = span > 0.0 ? std::clamp((t[i] - (a.t_s - t0)) / span, 0.0, 1.0) : 0.0;
    const auto row = static_cast<Eigen::Index>(i);
    out.p_xy.row(row) = ((1.0 - w) * a.p_WT.head<2>() + w * b.p_WT.head<2>()).transpose();
    out.f_guide.row(row) = ((1.0 - w) * a.f_guide_W + w * b.f_guide_W).transpose();
    out.pen_down[i] = static_cast<char>(w < 0.5 ? a.pen_down : b.pen_down);
    out.valid[i] = 1;
  }
  return out;
}

// Where Eigen's product of phi by three columns is its blocked one, summing each entry in one
// block: more than one row (one row is a vector product), rows + depth + 3 columns at least
// EIGEN_GEMM_TO_COEFFBASED_THRESHOLD (20; smaller products go coefficient by coefficient), and
// at most 128 basis functions (its depth blocks hold more with a 32 kB L1 data cache, the least
// of an x86-64 CPU and Eigen's default there, even with AVX-512's wider panels).
bool sumsInOneBlock(const Eigen::MatrixXd& phi) {
  return phi.rows() >= 2 && phi.rows() + phi.cols() + 3 >= 20 && phi.cols() <= 128;
}

}  // namespace

namespace detail {

Eigen::MatrixXd combineBasis(const Eigen::MatrixXd& phi, const PlanWeights& weights,
                             std::initializer_list<Eigen::Index> columns) {
  HATTR_DEMAND(columns.size() >= 1 && columns.size() <= 3, "combineBasis: expected 1 to 3 columns, got {}",
               columns.size());
  Eigen::MatrixXd out(phi.rows(), static_cast<Eigen::Index>(columns.size()));
  if (!sumsInOneBlock(phi)) {
    const Eigen::MatrixX3d product = phi * weights;
    Eigen::Index j = 0;
    for (const Eigen::Index c : columns) out.col(j++) = product.col(c);
    return out;
  }
  // Every matrix here is stored by columns.
  BasisCombination c{.phi = phi.data(), .rows = static_cast<std::size_t>(phi.rows()),
                     .functions = static_cast<std::size_t>(phi.cols()), .columns = columns.size()};
  Eigen::Index j = 0;
  for (const Eigen::Index col : columns) {
    c.weights[j] = weights.col(col).data();
    c.out[j] = out.col(j).data();
    ++j;
  }
  combineBasisColumns(c);
  return out;
}

}  // namespace detail

double perceivedForce(double force_N, double weber_fraction, double standard_normal) noexcept {
  return force_N * (1.0 + weber_fraction * standard_normal);
}

SimulatedTrainee::SimulatedTrainee(const TraineeModel& model, const SubjectTraits& traits,
                                   const HapticProfile& template_script, std::uint64_t seed)
    : traits_(traits),
      basis_(static_cast<int>(model.basis_count.value), model.basis_width_ratio.value),
      seed_(seed),
      hypothesis_(model.hypothesis),
      metadata_(template_script.metadata()) {
  validateTraits(traits_);
  HATTR_THROW_UNLESS(template_script.size() >= 2 && template_script.duration_s() > 0.0,
                     "simulated trainee: template: expected at least two samples over a positive duration, got {}",
                     template_script.size());
  HATTR_THROW_UNLESS(model.projection_ridge.value >= 0.0 && model.projection_ridge.value <= 1.0,
                     "simulated trainee: projection_ridge: expected [0, 1], got {}", model.projection_ridge.value);

  // The template on its own grid.
  const auto& samples = template_script.samples();
  const auto n = static_cast<Eigen::Index>(samples.size());
  const bool has_tilt = template_script.rawChannels().tilt;
  const double t0 = samples.front().t_s;
  duration_s_ = samples.back().t_s - t0;
  t_s_.resize(samples.size());
  template_xy_.resize(n, 2);
  template_v_xy_.resize(n, 2);
  template_z_.resize(n);
  template_axial_N_.resize(n);
  altitude_rad_.resize(n);
  sin_altitude_.resize(n);
  azimuth_rad_.resize(n);
  pen_down_.resize(samples.size());
  std::vector<double> u(samples.size());
  for (Eigen::Index i = 0; i < n; ++i) {
    const Sample& s = samples[static_cast<std::size_t>(i)];
    t_s_[static_cast<std::size_t>(i)] = s.t_s - t0;
    u[static_cast<std::size_t>(i)] = (s.t_s - t0) / duration_s_;
    template_xy_.row(i) = s.p_WT.head<2>().transpose();
    template_v_xy_.row(i) = s.v_WT.head<2>().transpose();
    template_z_(i) = s.p_WT.z();
    altitude_rad_(i) = has_tilt ? std::clamp(s.tilt_altitude_rad, 0.1, 1.5707963267948966) : kDefaultAltitude_rad;
    azimuth_rad_(i) = has_tilt ? s.tilt_azimuth_rad : 0.0;
    pen_down_[static_cast<std::size_t>(i)] = static_cast<char>(s.pen_down);
    sin_altitude_(i) = std::sin(altitude_rad_(i));
    template_axial_N_(i) = s.pen_down ? std::max(-s.f_user_W.z(), 0.0) / sin_altitude_(i) : 0.0;
  }
  visual_xy_ = template_xy_;
  visual_pen_down_ = pen_down_;

  // The basis on the template's normalized time.
  phi_ = basis_.design(u);
  phi_rate_ = basis_.designDerivative(u) / duration_s_;
  phi_mass_ = phi_.colwise().sum().transpose();
  ridge_ = model.projection_ridge.value * (phi_.array().square().sum() / static_cast<double>(basis_.size()));

  const auto k = static_cast<Eigen::Index>(basis_.size());
  fast_ = PlanWeights::Zero(k, 3);
  slow_ = PlanWeights::Zero(k, 3);
  deviation_ = PlanWeights::Zero(k, 3);

  // The personal deviation: independent normal weights, scaled so that the smooth field they
  // make has the trainee's RMS over the trial.
  detail::NormalSource normal(detail::streamSeed(seed_, kDeviationStream));
  Eigen::MatrixX2d raw(k, 2);
  for (Eigen::Index r = 0; r < k; ++r) {
    for (Eigen::Index c = 0; c < 2; ++c) raw(r, c) = normal.normal();
  }
  const Eigen::MatrixX2d field = phi_ * raw;
  const double rms = std::sqrt(field.rowwise().squaredNorm().mean());
  if (rms > 0.0) deviation_.leftCols<2>() = raw * (traits_.deviation_rms_m * planUnitsPerMetre() / rms);
}

double SimulatedTrainee::planUnitsPerMetre() const noexcept {
  // A force plan moves the path by its force over the grip's stiffness: a path offset of
  // d needs a push of grip × K × d (K: the hand's stiffness, felt_force_stiffness_N_per_m).
  return hypothesis_ == LearningHypothesis::kForcePlan ? traits_.grip_ratio * traits_.felt_force_stiffness_N_per_m
                                                       : 1.0;
}

SimulatedTrainee::Series SimulatedTrainee::series(const PlanWeights& weights, SeriesUse use) const {
  // Only the columns the use reads are combined, the offsets in one pass over the basis (the
  // rate of the axial force is never read).
  const bool played = use == SeriesUse::kPlayed;
  const bool force_plan = hypothesis_ == LearningHypothesis::kForcePlan;
  const Eigen::MatrixXd offsets = played ? detail::combineBasis(phi_, weights, {kPlanX, kPlanY, kPlanAxialForce})
                                         : detail::combineBasis(phi_, weights, {kPlanAxialForce});
  Series s;
  s.v_xy = template_v_xy_;
  if (!force_plan) s.v_xy += detail::combineBasis(phi_rate_, weights, {kPlanX, kPlanY});
  if (played) {
    s.p_xy = template_xy_;
    s.push_xy = Eigen::MatrixX2d::Zero(template_xy_.rows(), 2);
    if (force_plan) {
      // A force plan: the hand aims at the template's path with its loose grip and pushes with
      // the friction the plan expects at the template's normal force, along the template's
      // motion, plus what it learned (in newtons). Pressing otherwise is not compensated.
      for (Eigen::Index i = 0; i < s.push_xy.rows(); ++i) {
        const double speed = template_v_xy_.row(i).norm();
        if (pen_down_[static_cast<std::size_t>(i)] && speed > 1e-6) {
          const double normal_N = template_axial_N_(i) * sin_altitude_(i);
          s.push_xy.row(i) = traits_.plan_friction * normal_N * template_v_xy_.row(i) / speed;
        }
      }
      s.push_xy += offsets.leftCols<2>();
    } else {
      s.p_xy += offsets.leftCols<2>();
    }
  }
  const auto axial_offsets = offsets.col(offsets.cols() - 1);
  s.axial_N.resize(template_axial_N_.size());
  for (Eigen::Index i = 0; i < s.axial_N.size(); ++i) {
    const double planned = traits_.force_scale * template_axial_N_(i) + traits_.force_offset_N + axial_offsets(i);
    s.axial_N(i) = pen_down_[static_cast<std::size_t>(i)] ? std::max(planned, 0.0) : 0.0;
  }
  return s;
}

HapticProfile SimulatedTrainee::profileOf(const Series& s, const std::string& source, double pace_factor) const {
  ProfileMetadata metadata = metadata_;
  metadata.source = source;
  HapticProfile profile(std::move(metadata), RawChannels{.tilt = true});
  profile.reserve(t_s_.size());
  for (std::size_t i = 0; i < t_s_.size(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    Sample sample;
    sample.t_s = t_s_[i] * pace_factor;
    sample.p_WT = Vec3(s.p_xy(r, 0), s.p_xy(r, 1), template_z_(r));
    // No vertical target velocity: pen up, the hand holds the pen at least 3 mm high whatever
    // the template's height (a recorded template falls onto the paper just before contact, and
    // its speed would drive the pen into it); pen down, the hand only presses.
    sample.v_WT = Vec3(s.v_xy(r, 0) / pace_factor, s.v_xy(r, 1) / pace_factor, 0.0);
    sample.pen_down = pen_down_[i] != 0;
    sample.in_contact = sample.pen_down;
    sample.f_user_W = Vec3(s.push_xy(r, 0), s.push_xy(r, 1), -s.axial_N(r) * sin_altitude_(r));
    sample.tilt_altitude_rad = altitude_rad_(r);
    sample.tilt_azimuth_rad = azimuth_rad_(r);
    profile.append(sample);
  }
  return profile;
}

void SimulatedTrainee::restDays(int days) {
  if (days > 0) fast_.setZero();
}

HapticProfile SimulatedTrainee::plan() const { return profileOf(series(planWeights()), "sim:trainee-plan"); }

std::unique_ptr<device::HandScript> SimulatedTrainee::handForTrial(std::uint64_t trial_seed) const {
  const PlanWeights weights = planWeights();
  const Series planned = series(weights, SeriesUse::kNoiseScale);
  // Signal-dependent noise (Harris & Wolpert 1998): per basis window, SD proportional to the
  // command there — the distance the plan covers in the window, and the planned axial force.
  const Eigen::VectorXd speed = planned.v_xy.rowwise().norm();
  const double window_s = basis_.spacing() * duration_s_;
  const Eigen::VectorXd mean_speed = (phi_.transpose() * speed).cwiseQuotient(phi_mass_);
  const Eigen::VectorXd mean_force = (phi_.transpose() * planned.axial_N).cwiseQuotient(phi_mass_);
  detail::NormalSource normal(detail::streamSeed(detail::streamSeed(seed_, kTrialNoiseStream), trial_seed));
  PlanWeights noise = PlanWeights::Zero(weights.rows(), 3);
  for (Eigen::Index k = 0; k < weights.rows(); ++k) {
    const double position_sd = traits_.position_noise_coefficient * mean_speed(k) * window_s * planUnitsPerMetre();
    noise(k, kPlanX) = position_sd * normal.normal();
    noise(k, kPlanY) = position_sd * normal.normal();
    noise(k, kPlanAxialForce) = traits_.force_noise_coefficient * mean_force(k) * normal.normal();
  }
  const HapticProfile trial = profileOf(series(weights + noise), "sim:trainee-hand", paceFactor(trial_seed));
  const bool force_plan = hypothesis_ == LearningHypothesis::kForcePlan;
  return std::make_unique<device::ProfileHandScript>(
      trial, kDefaultAltitude_rad, Vec3::Zero(),
      device::ProfilePlayback{.grip = force_plan ? traits_.grip_ratio : 1.0, .push_in_plane = force_plan});
}

double SimulatedTrainee::paceFactor(std::uint64_t trial_seed) const {
  // The whole movement faster or slower, its relative timing kept (homothety, Viviani &
  // Terzuolo 1980); the size of the variation is data/sim/trainee_model.json's pace_cv.
  detail::NormalSource normal(detail::streamSeed(detail::streamSeed(seed_, kPaceStream), trial_seed));
  return std::clamp(std::exp(traits_.pace_cv * normal.normal()), 0.5, 2.0);
}

const SimulatedTrainee::Projection& SimulatedTrainee::projectionFor(const std::vector<char>& mask) {
  // Two slots, the least recently used replaced: learn's felt mask (the same trial after trial)
  // stays while its visual one changes.
  for (std::size_t k = 0; k < projections_.size(); ++k) {
    if (!projections_[k].mask.empty() && projections_[k].mask == mask) {
      next_projection_ = 1 - k;
      return projections_[k];
    }
  }
  Projection& p = projections_[next_projection_];
  next_projection_ = 1 - next_projection_;
  p.mask = mask;
  p.phi_masked = phi_;
  for (std::size_t i = 0; i < mask.size(); ++i) {
    if (!mask[i]) p.phi_masked.row(static_cast<Eigen::Index>(i)).setZero();
  }
  Eigen::MatrixXd gram = p.phi_masked.transpose() * p.phi_masked;
  gram.diagonal().array() += ridge_;
  p.empty = gram.diagonal().maxCoeff() <= 0.0;
  if (!p.empty) p.gram.compute(gram);
  return p;
}

Eigen::MatrixXd SimulatedTrainee::project(const Eigen::MatrixXd& values, const std::vector<char>& mask) {
  const Projection& p = projectionFor(mask);
  if (p.empty) return Eigen::MatrixXd::Zero(p.phi_masked.cols(), values.cols());
  const Eigen::MatrixXd rhs = p.phi_masked.transpose() * values;
  return p.gram.solve(rhs);
}

void SimulatedTrainee::learn(const HapticProfile& recorded, bool template_shown, double pace_factor) {
  HATTR_THROW_UNLESS(recorded.size() >= 2, "simulated trainee: learn: expected a recorded trial of at least two samples, got {}",
                     recorded.size());
  HATTR_THROW_UNLESS(std::isfinite(pace_factor) && pace_factor >= 0.5 && pace_factor <= 2.0,
                     "simulated trainee: learn: pace factor: expected [0.5, 2], got {}", pace_factor);
  // The recording at the same points of the movement as the template's grid.
  std::vector<double> t_recorded(t_s_.size());
  for (std::size_t i = 0; i < t_s_.size(); ++i) t_recorded[i] = t_s_[i] * pace_factor;
  const Resampled rec = resample(recorded, t_recorded);  // both start at 0: they always overlap
  const auto k = static_cast<Eigen::Index>(basis_.size());
  PlanWeights error = PlanWeights::Zero(k, 3);

  // (a) What the trainee sees: the template against its own trace, where both have ink.
  if (template_shown) {
    std::vector<char> mask(t_s_.size());
    for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = static_cast<char>(rec.valid[i] && visual_pen_down_[i] && rec.pen_down[i]);
    const Eigen::MatrixXd visual_error = visual_xy_ - rec.p_xy;
    error.leftCols<2>() += ownLearningShare(rec.f_guide, rec.valid) * planUnitsPerMetre() * project(visual_error, mask);
  }

  // (b) What the trainee felt: the guidance force, as an in-plane force and as the axial force
  // that would give its normal part, perceived with Weber noise, read as a plan error. A trial
  // without guidance felt none: its weights would all be zero, which add nothing to the error
  // (whose entries are never -0), so they are not computed.
  if (!rec.f_guide.isZero(0.0)) error += feltError(rec.f_guide, rec.valid);

  // The one learning rule.
  fast_ = traits_.fast_retention * fast_ + traits_.fast_rate * error;
  slow_ = traits_.slow_retention * slow_ + traits_.slow_rate * error;
  ++trials_learned_;
}

PlanWeights SimulatedTrainee::feltError(const Eigen::MatrixX3d& f_guide, const std::vector<char>& valid) {
  Eigen::MatrixXd felt(static_cast<Eigen::Index>(t_s_.size()), 3);
  felt.leftCols<2>() = f_guide.leftCols<2>();
  felt.col(2) = -f_guide.col(2).cwiseQuotient(altitude_rad_.array().sin().matrix());
  Eigen::MatrixXd felt_weights = project(felt, valid);
  detail::NormalSource normal(
      detail::streamSeed(detail::streamSeed(seed_, kPerceptionStream), static_cast<std::uint64_t>(trials_learned_)));
  for (Eigen::Index r = 0; r < felt_weights.rows(); ++r) {
    for (Eigen::Index c = 0; c < 3; ++c) {
      felt_weights(r, c) = perceivedForce(felt_weights(r, c), traits_.weber_fraction, normal.normal());
    }
  }
  // A position plan reads the in-plane force as where the hand should have been (f / K); a
  // force plan takes it as force it should have pushed with.
  PlanWeights error(felt_weights.rows(), 3);
  if (hypothesis_ == LearningHypothesis::kForcePlan) {
    error.col(kPlanX) = felt_weights.col(0);
    error.col(kPlanY) = felt_weights.col(1);
  } else {
    error.col(kPlanX) = felt_weights.col(0) / traits_.felt_force_stiffness_N_per_m;
    error.col(kPlanY) = felt_weights.col(1) / traits_.felt_force_stiffness_N_per_m;
  }
  error.col(kPlanAxialForce) = felt_weights.col(2);
  return error;
}

double SimulatedTrainee::ownLearningShare(const Eigen::MatrixX3d& f_guide, const std::vector<char>& valid) const {
  if (hypothesis_ != LearningHypothesis::kGuidanceDependent) return 1.0;
  // The guidance hypothesis: in a trial whose guidance it felt, the trainee leans on it and
  // learns less from its own error.
  double sum = 0.0;
  int count = 0;
  for (std::size_t i = 0; i < valid.size(); ++i) {
    if (!valid[i]) continue;
    sum += f_guide.row(static_cast<Eigen::Index>(i)).squaredNorm();
    ++count;
  }
  const double rms_N = count > 0 ? std::sqrt(sum / count) : 0.0;
  return rms_N > traits_.guidance_felt_N ? 1.0 - traits_.guidance_dependence : 1.0;
}

void SimulatedTrainee::setVisualTemplate(const HapticProfile& shown) {
  HATTR_THROW_UNLESS(shown.size() >= 2, "simulated trainee: visual template: expected at least two samples, got {}",
                     shown.size());
  const Resampled r = resample(shown, t_s_);
  visual_xy_ = r.p_xy;
  visual_pen_down_.assign(t_s_.size(), 0);
  for (std::size_t i = 0; i < t_s_.size(); ++i) visual_pen_down_[i] = static_cast<char>(r.valid[i] && r.pen_down[i]);
}

}  // namespace hattr::sim
