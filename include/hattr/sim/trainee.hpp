#pragma once
/// The simulated trainee (docs/simulation.md): a movement plan and an axial-force plan held
/// as offsets from the expert's template on a smooth basis over normalized time, played on
/// the simulated pen by a hand with signal-dependent motor noise, and updated after every
/// trial by one learning rule — the same in every mode and phase — with a fast and a slow
/// state (Smith, Ghazizadeh & Shadmehr 2006), driven by
///   (a) the visual error against the template, when the template is shown, and
///   (b) the guidance force the trainee felt, perceived with Weber noise, read as a plan
///       error in the force's direction (Emken et al. 2007): in-plane force / K → position,
///       normal force / sin(altitude) → axial force.
/// A training mode enters only through (b): the recording's f_guide_W channel.
///
/// That is the position-plan learner; the model's hypothesis (LearningHypothesis) may change
/// it: a force-plan learner holds x and y as a push [N] the hand adds with a loose grip (the
/// path it aims at stays the template's) and takes a felt in-plane force as push; a
/// guidance-dependent learner learns less of (a) after a trial whose guidance it felt.
///
/// Plan channels are the columns of every weight matrix: x [m], y [m], axial force [N]
/// (force-plan: push x [N], push y [N], axial force [N]).
/// Everything is seeded: the same model, traits, template and seed give the same trainee,
/// and the same trial seed the same noise, so modes can be compared on common random numbers.

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/sim/basis.hpp"
#include "hattr/sim/trainee_model.hpp"

namespace hattr::sim {

/// Columns of the plan's weight matrices.
enum PlanChannel : int { kPlanX = 0, kPlanY = 1, kPlanAxialForce = 2 };

/// K × 3 weights on the basis, one column per PlanChannel.
using PlanWeights = Eigen::Matrix<double, Eigen::Dynamic, 3>;

/// A force as a trainee perceives it: force_N × (1 + weber_fraction × standard_normal), where
/// `standard_normal` is a draw from N(0, 1): a relative SD of weber_fraction (Weber's law; about
/// 7 % for force, Jones 1989). Any unit. Pure and noexcept.
double perceivedForce(double force_N, double weber_fraction, double standard_normal) noexcept;

class SimulatedTrainee {
 public:
  /// A trainee of `traits` learning `template_script`: its path, velocity, pen-down flags, normal
  /// force f_user_W.z and tilt (without tilt channels an altitude of 60° and azimuth 0 are assumed,
  /// as device::ProfileHandScript does). Use the expert's script (expertScript): what the expert
  /// meant to do. A recording is accepted, but its force starts only at contact, so a hand replaying
  /// it drops the pen onto the paper already pressing, late and hard; show the recording with
  /// setVisualTemplate instead. The basis
  /// comes from `model`. `seed` draws the trainee's personal plan deviation (a smooth random
  /// offset field scaled to traits.deviation_rms_m RMS over the trial) and its perception noise.
  /// Throws InputError for invalid traits, a template of fewer than two samples, or a model
  /// whose basis cannot be built. Not for the servo thread.
  SimulatedTrainee(const TraineeModel& model, const SubjectTraits& traits, const HapticProfile& template_script,
                   std::uint64_t seed);

  /// The hand for one trial: the current plan plus signal-dependent motor noise drawn with
  /// `trial_seed` (combined with the trainee's seed): per basis window, position noise of SD
  /// position_noise_coefficient × the distance the plan covers in the window, and axial-force
  /// noise of SD force_noise_coefficient × the planned force in the window. The script runs on
  /// the trial's clock from t = 0 (a device::ProfileHandScript over the noisy plan; it holds the
  /// last point after the end). Not for the servo thread; the returned script's command() is.
  /// The trial is played at the trial's pace (paceFactor): its clock stretched by that factor,
  /// its velocities divided by it.
  [[nodiscard]] std::unique_ptr<device::HandScript> handForTrial(std::uint64_t trial_seed) const;

  /// The pace of the trial drawn with `trial_seed` (its own stream): the factor by which the
  /// trial lasts longer than the plan, exp(traits.pace_cv × N(0, 1)) kept within [0.5, 2].
  /// The same seed gives the same factor (a resumed study replays its trials). Pure.
  [[nodiscard]] double paceFactor(std::uint64_t trial_seed) const;

  /// Updates the plan after a trial (times from 0, as session::runTrial records them):
  ///   e = [visual error if template_shown] + [felt guidance force, perceived and converted],
  ///   each projected onto the basis (least squares with the model's ridge);
  ///   fast ← A_f·fast + B_f·e,  slow ← A_s·slow + B_s·e.
  /// The visual error is template − recorded position in the plane, where both the shown
  /// template and the recording have the pen down. Recorded samples after the template's end are
  /// ignored. With the template hidden (recall) there is no visual error: the trainee has only
  /// what it felt, and with no guidance both states decay by their retention factors. A
  /// force-plan learner converts the visual error to push (× grip × K) and takes the felt
  /// in-plane force as push; a guidance-dependent one scales the visual error by
  /// 1 − guidance_dependence after a trial whose guidance RMS exceeded guidance_felt_N. Throws
  /// InputError for a recording of fewer than two samples. Not for the servo thread.
  /// `pace_factor`: the trial's paceFactor; the trainee compares the template with its own
  /// trace at the same point of the movement (recorded time / pace_factor), not of the clock.
  void learn(const HapticProfile& recorded_trial, bool template_shown, double pace_factor = 1.0);

  /// Days pass between sessions (days > 0; nothing for 0): the fast state is forgotten and
  /// the slow state kept, whatever the hypothesis. The fast process forgets within minutes
  /// (its retention A_f per trial, Smith, Ghazizadeh & Shadmehr 2006), and what is retained a
  /// day later is predicted by the slow process alone (Joiner & Smith 2008, Long-term
  /// retention explained by a model of short-term learning in the adaptive control of
  /// reaching, J Neurophysiol 100:2948-2955). No offline gain (consolidation adds nothing
  /// here), and no further forgetting over longer delays: hattr's reading, fixed before any
  /// comparison was run (docs/simulation.md "Between sessions").
  void restDays(int days);

  /// What the trainee sees as the template in training trials (default: the template script
  /// itself), e.g. the expert's recording the study displays. Its path and pen-down flags are
  /// used, on the template's clock. Throws InputError for fewer than two samples.
  void setVisualTemplate(const HapticProfile& shown);

  /// The current plan without noise, on the template's time grid: what handForTrial plays with
  /// zero noise. Positions, velocities, pen-down and tilt as a profile; f_user_W.z is the planned
  /// normal force −axial·sin(altitude), f_user_W.x and .y the planned push (force-plan; else 0). The height is the template's, its velocity zero (the hand
  /// holds the pen up at least 3 mm, or presses it down: it never tracks a vertical speed).
  [[nodiscard]] HapticProfile plan() const;

  /// The learning states and the personal deviation, K × 3 (x [m], y [m], axial force [N]).
  [[nodiscard]] const PlanWeights& fastState() const noexcept { return fast_; }
  [[nodiscard]] const PlanWeights& slowState() const noexcept { return slow_; }
  [[nodiscard]] const PlanWeights& deviation() const noexcept { return deviation_; }

  [[nodiscard]] const SubjectTraits& traits() const noexcept { return traits_; }
  [[nodiscard]] const NormalizedGaussianBasis& basis() const noexcept { return basis_; }
  /// Number of learn() calls so far.
  [[nodiscard]] int trialsLearned() const noexcept { return trials_learned_; }
  /// The template's duration [s].
  [[nodiscard]] double duration_s() const noexcept { return duration_s_; }

 private:
  struct Series {
    Eigen::MatrixX2d p_xy;    // planned position in the plane [m]
    Eigen::MatrixX2d v_xy;    // planned velocity [m/s]
    Eigen::MatrixX2d push_xy; // planned in-plane push (force plan only, else 0) [N]
    Eigen::VectorXd axial_N;  // planned axial force (0 with the pen up) [N]
  };
  /// Plan units of the x, y channels per metre of path: 1 for a position plan, N/m for a force plan.
  [[nodiscard]] double planUnitsPerMetre() const noexcept;
  /// The share of its own (visual) error the trainee learns from after a trial that felt the
  /// guidance `f_guide` (rows where `valid`): guidance-dependent, less after a guided trial; else 1.
  [[nodiscard]] double ownLearningShare(const Eigen::MatrixX3d& f_guide, const std::vector<char>& valid) const;
  /// learn()'s error from the guidance felt (`f_guide` on the template's grid, rows where `valid`),
  /// in plan units, perceived with this trial's Weber noise.
  [[nodiscard]] PlanWeights feltError(const Eigen::MatrixX3d& f_guide, const std::vector<char>& valid);
  /// What a series is for: the hand plays it (all of it), or only the trial noise scales with
  /// it (the planned velocity and axial force; the positions and pushes are left empty).
  enum class SeriesUse { kPlayed, kNoiseScale };
  [[nodiscard]] Series series(const PlanWeights& weights, SeriesUse use = SeriesUse::kPlayed) const;
  [[nodiscard]] HapticProfile profileOf(const Series& s, const std::string& source, double pace_factor = 1.0) const;
  [[nodiscard]] PlanWeights planWeights() const { return deviation_ + fast_ + slow_; }
  /// Least-squares weights of `values` (N × c) over the masked samples.
  [[nodiscard]] Eigen::MatrixXd project(const Eigen::MatrixXd& values, const std::vector<char>& mask);
  /// The basis over the masked samples and its factored Gram matrix, kept for the next mask
  /// that is the same (most trials' felt mask is): the same numbers, computed once.
  struct Projection {
    std::vector<char> mask;
    Eigen::MatrixXd phi_masked;       // N × K, rows outside the mask zero
    Eigen::LDLT<Eigen::MatrixXd> gram;  // of phi_masked, plus the ridge
    bool empty = true;                // no masked sample: the weights are zero
  };
  const Projection& projectionFor(const std::vector<char>& mask);

  SubjectTraits traits_;
  NormalizedGaussianBasis basis_;
  double ridge_ = 0.0;                  // absolute ridge of the projection
  std::uint64_t seed_;
  LearningHypothesis hypothesis_;
  ProfileMetadata metadata_;

  // The template on its own time grid (times relative to its first sample).
  std::vector<double> t_s_;
  double duration_s_ = 0.0;
  Eigen::MatrixX2d template_xy_;
  Eigen::MatrixX2d template_v_xy_;
  Eigen::VectorXd template_z_;
  Eigen::VectorXd template_axial_N_;
  std::vector<char> pen_down_;
  Eigen::VectorXd altitude_rad_;
  Eigen::VectorXd sin_altitude_;  // std::sin of altitude_rad_, for every plan played
  Eigen::VectorXd azimuth_rad_;

  Eigen::MatrixXd phi_;        // N × K basis values
  Eigen::MatrixXd phi_rate_;   // N × K time derivatives [1/s]
  Eigen::VectorXd phi_mass_;   // K: column sums of phi_

  // What the trainee sees in training trials, on the template's grid.
  Eigen::MatrixX2d visual_xy_;
  std::vector<char> visual_pen_down_;

  PlanWeights deviation_;
  PlanWeights fast_;
  PlanWeights slow_;
  int trials_learned_ = 0;
  std::array<Projection, 2> projections_;  // the last two masks' (learn's visual and felt)
  std::size_t next_projection_ = 0;       // the one replaced next: the least recently used
};

}  // namespace hattr::sim
