#pragma once
/// The studio's main window: the paper view and the haptic-profile plot beside six tabs —
/// Write (free writing), Record (an expert's take), Train (a trial against a reference in
/// BASIC, PCONTROL or ALPHA, scored by DTW), Study (a person's study session from a study
/// database), Review (a study's subjects and trials, overlaid on the expert and played
/// back) and Mentor (live mentoring over the network, ui/mentor_tab.hpp). One live rig runs
/// the servo loop in real time on the simulated pen the mouse holds (a mentoring session
/// takes the device and the hand over while it runs); the window reads the loop's newest
/// sample at display rate and never waits on it.
/// Every action is also a public member, so tests (and scripts) drive what a person drives.

#include <QElapsedTimer>
#include <QMainWindow>
#include <QSettings>
#include <QUrl>
#include <functional>
#include <memory>
#include <optional>

#include "core/live_rig.hpp"
#include "core/mouse_hand.hpp"
#include "core/series.hpp"
#include "core/trial_scoring.hpp"

class QAction;
class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QLabel;
class QLineEdit;
class QPushButton;
class QSlider;
class QSplitter;
class QTabWidget;
class QTimer;

namespace hattr::studio {

class LearnersTab;
class LearningCurve;
class MentorTab;
class PaperView;
class PenSceneView;
class ProfilePlot;
class RecordTab;
class ReviewTab;
class StudySession;
class StudyTab;
class TrainTab;
struct TakeName;

class MainWindow final : public QMainWindow {
  Q_OBJECT

 public:
  /// What the rig and the view are doing.
  enum class Activity { kFree, kRecording, kTrial, kStudyTrial, kPlayback, kMentoring };
  enum Tab : int { kTabWrite = 0, kTabRecord, kTabTrain, kTabStudy, kTabReview, kTabMentor, kTabLearners };

  /// `settings`: where settings are remembered (null: QSettings "hattr"/"studio").
  explicit MainWindow(std::unique_ptr<QSettings> settings = nullptr, QWidget* parent = nullptr);
  ~MainWindow() override;

  /// Interactive (default): errors in dialogs, questions asked. Otherwise (tests) errors are
  /// kept in lastError() and every question is answered `answer`.
  void setInteractive(bool interactive, bool answer = false);
  [[nodiscard]] const QString& lastError() const { return last_error_; }

  // ---- Actions (the buttons, menus and shortcuts call these); false when refused. ------
  /// Loads a reference profile for training (Train tab).
  bool loadReference(const QString& file);
  /// Makes the current take the training reference, unsaved (Record tab); the Train tab opens.
  bool useTakeAsReference();
  /// Loads a world configuration (paper, friction, relief) for writing and training.
  bool loadWorld(const QString& file);
  /// The training mode; during a trial it switches through the servo mailbox (cross-fade).
  void setMode(guidance::TrainingMode mode);
  bool startTrial();
  /// The stop key (Ctrl+.): ends the running training or study trial now and keeps it, as if
  /// it had ended by itself (scored, or stored in the study database), its end_reason
  /// "stopped"; stops a recording and keeps the take. A trial still in its get-ready phase has
  /// recorded nothing: it is aborted (a study trial runs again). False when nothing runs.
  bool stopTrial();
  /// Stops a running trial or recording without keeping it; stops a playback.
  void abortActivity();
  bool startRecording();
  bool stopRecording();
  /// Saves the current take as a haptic profile (refuses to replace a file unless confirmed).
  bool saveTake(const QString& file);
  /// Saves the last trial (also after a study database refused it).
  bool saveLastTrial(const QString& file);
  bool openStudy(const QString& file);
  bool selectStudySubject(const QString& subject);
  /// Study: cut the rest short / start the next trial.
  bool studyNext();
  void closeStudy();
  bool openReview(const QString& file);
  /// Review: shows the trial with this database id overlaid on the expert.
  bool showReviewTrial(qint64 trial_id);
  /// Plays back (or pauses) the profile on show: a take, the last trial or a reviewed trial.
  void togglePlayback();
  void clearTrail();
  /// The device for the live rig, by URI (sim://, plugin:, udp://, serial://); applied to the
  /// rig at once when nothing runs (a study keeps its own device). Remembered in settings.
  bool setDevice(const QString& uri);
  [[nodiscard]] QString deviceUri() const;
  /// A tablet calibration JSON (io::loadCalibration over defaultTabletCalibration()).
  bool loadTabletCalibration(const QString& file);
  /// Review: analyzes the open study, writes its report next to the database
  /// (<stem>-report/) and opens report.html with the URL opener.
  bool openReport();
  /// Who opens URLs (default QDesktopServices::openUrl); tests replace it.
  void setUrlOpener(std::function<bool(const QUrl&)> opener) { url_opener_ = std::move(opener); }
  /// The tab's main action (Space): record/stop, start/stop a trial, the study's next step, play/pause.
  void primaryAction();
  /// The first size and place on the window's screen: the size remembered, else 1280 × 820,
  /// within the screen's available area (less the frame) so the status bar is on the screen,
  /// and moved onto it. Called by hattr-studio before and after show().
  void fitToScreen();
  /// View ▸ Engineer view (Ctrl+E, remembered): the loop's counters, DTW units, technical
  /// strategy names, the mentoring station's passivity and deadband. Off (the default), the
  /// studio speaks plainly: strategies by their plain names, scores as "lower is closer", the
  /// loop only when it does not keep time.
  void setEngineerView(bool on);
  [[nodiscard]] bool engineerView() const { return engineer_view_; }

  [[nodiscard]] Activity activity() const { return activity_; }
  /// The Train tab's mode.
  [[nodiscard]] guidance::TrainingMode mode() const;
  [[nodiscard]] const std::optional<analysis::TrialScore>& lastScores() const { return last_scores_; }
  [[nodiscard]] const std::optional<HapticProfile>& lastTrial() const { return last_trial_; }
  /// The Record tab's take (none before one is recorded).
  [[nodiscard]] const std::optional<HapticProfile>& take() const;
  /// The open study session (null: none); the Study tab owns it.
  [[nodiscard]] StudySession* study() const;
  [[nodiscard]] PaperView* paperView() const { return paper_; }
  /// The tool bar's Paper box: the whole paper or its middle 2, 3 or 4 times larger (remembered).
  [[nodiscard]] QComboBox* zoomBox() const { return zoom_box_; }
  /// The 3-D view beside the paper (shown with the tool bar's "3-D view", remembered).
  [[nodiscard]] PenSceneView* sceneView() const { return scene_; }
  void setSceneShown(bool shown);
  [[nodiscard]] ProfilePlot* plot() const { return plot_; }
  [[nodiscard]] MouseHand& mouseHand() { return hand_; }
  [[nodiscard]] LiveRig& rig() { return rig_; }
  [[nodiscard]] QTabWidget* tabs() const { return tabs_; }
  [[nodiscard]] MentorTab* mentorTab() const { return mentor_; }
  [[nodiscard]] ReviewTab* reviewTab() const { return review_; }
  [[nodiscard]] StudyTab* studyTab() const { return study_tab_; }
  [[nodiscard]] RecordTab* recordTab() const { return record_tab_; }
  [[nodiscard]] LearningCurve* learningCurve() const;
  [[nodiscard]] TrainTab* trainTab() const { return train_tab_; }
  [[nodiscard]] LearnersTab* learnersTab() const { return learners_tab_; }

 protected:
  void closeEvent(QCloseEvent* event) override;

 private:
  // Construction (main_window.cpp).
  void buildUi();
  void buildToolBar();
  void buildStatusBar();
  void buildWriteTab();
  void buildRecordTab();
  void buildTrainTab();
  void buildStudyTab();
  void buildReviewTab();
  void buildMentorTab();
  void buildLearnersTab();
  /// The Learners tab's Continue: the plan open in the Study tab, the learner picked, their next
  /// session begun (asking first when it is early).
  bool continuePlan(const QString& file, const QString& learner);
  void buildActions();
  void buildFileMenu();
  void buildActionsMenu();
  void buildViewMenu();
  void buildHelpMenu();
  void loadSettings();
  void saveSettings();

  // The loop and the display (main_window.cpp).
  /// The rig's free run on the current environment (its one open of the device); errors shown.
  void startFreeRun();
  /// The same, returning why it could not start ("" when it runs) instead of showing it.
  QString tryFreeRun();
  /// Makes `environment` the rig's and starts its free run (which opens the device; the paper
  /// view then takes its limits). Returns why the free run could not start, "" when it runs.
  QString useEnvironment(session::TrialEnvironment& environment);
  /// useEnvironment, with any failure shown.
  void startFreeRunOn(session::TrialEnvironment& environment);
  void onFrame();
  void onStatus();
  void consumeLive(const Sample& sample);
  /// Starts a live trial of `setup` on `environment` as `kind` (a training or a study trial)
  /// against `expert`: drawn on the paper when `reference_on_paper`, its force on the plot
  /// when `expert_on_plot`; the plot titled `title`, `scores` says it runs. Throws what the
  /// rig throws (free writing goes on).
  void beginLiveTrial(session::TrialEnvironment& environment, const session::TrialSetup& setup, Activity kind,
                      const HapticProfile& expert, bool reference_on_paper, bool expert_on_plot, const QString& title,
                      QLabel* scores);
  void finishTrial();
  /// Starts the rig on `environment` for a run of `kind` (a playback stops first); a run that
  /// cannot start leaves the free writing going and throws what the rig threw.
  void startRun(session::TrialEnvironment& environment, const RunSpec& spec, Activity kind);
  /// Nothing runs on the rig but the free writing (a playback may play).
  [[nodiscard]] bool idle() const { return activity_ == Activity::kFree || activity_ == Activity::kPlayback; }
  void showScores(const HapticProfile& expert, const HapticProfile& trial, QLabel* where);
  void showReference(const HapticProfile* expert);
  /// How the Record tab names its take, for the Train tab's reference.
  [[nodiscard]] TakeName takeName() const;
  void refreshButtons();
  /// The Write tab's device and world line (the clamps in the engineer view).
  void refreshWorldLabel();
  [[nodiscard]] double now_s() const;

  // Dialogs.
  void showError(const QString& what, const QString& detail);
  bool confirm(const QString& question);
  QString askSaveFile(const QString& title, const QString& suggested);
  QString askOpenFile(const QString& title, const QString& filter);
  /// The Device… dialog: asks for a URI and applies it.
  void askDevice();

  // Actions helpers (main_window_actions.cpp).
  /// Review: `trial` over `expert` on the paper and the plot, its scores in `scores`.
  void showReviewed(const HapticProfile& trial, const HapticProfile& expert, const QString& title, QLabel* scores);
  void startPlayback(const HapticProfile* profile, const HapticProfile* expert);
  bool saveProfileTo(const HapticProfile& profile, const QString& file, bool& saved_flag);

  std::unique_ptr<QSettings> settings_;
  QElapsedTimer clock_;
  bool interactive_ = true;
  bool answer_ = false;
  bool engineer_view_ = false;
  QAction* engineer_action_ = nullptr;
  bool geometry_restored_ = false;  // a size was remembered
  QString last_error_;

  // The live rig on the mouse's hand.
  MouseHand hand_;
  LiveRig rig_;
  std::unique_ptr<session::TrialEnvironment> default_environment_;
  session::TrialEnvironment* environment_ = nullptr;
  QString world_file_;
  Activity activity_ = Activity::kFree;
  Sample latest_{};
  bool plot_holds_result_ = false;  // the plot shows a trial or take until the pen writes again

  // The last trial (training or study) and its scores.
  std::optional<HapticProfile> last_trial_;
  std::optional<HapticProfile> last_trial_expert_;
  bool last_trial_saved_ = true;
  std::optional<analysis::TrialScore> last_scores_;
  const HapticProfile* trial_expert_ = nullptr;  // the reference of the running trial

  // Review.
  std::function<bool(const QUrl&)> url_opener_;
  QString tablet_calibration_file_;

  // Playback.
  Playback playback_;
  const HapticProfile* playback_expert_ = nullptr;
  Activity before_playback_ = Activity::kFree;

  // Status bar counters.
  std::uint64_t last_ticks_ = 0;
  double last_status_s_ = 0.0;
  double loop_rate_hz_ = 0.0;

  // Widgets.
  PaperView* paper_ = nullptr;
  PenSceneView* scene_ = nullptr;
  ProfilePlot* plot_ = nullptr;
  QSplitter* splitter_ = nullptr;
  QSplitter* left_splitter_ = nullptr;
  QSplitter* view_splitter_ = nullptr;  // the top view and the 3-D view
  QTabWidget* tabs_ = nullptr;
  QTimer* frame_timer_ = nullptr;
  QTimer* status_timer_ = nullptr;
  QSlider* press_slider_ = nullptr;
  QLabel* press_label_ = nullptr;
  QCheckBox* arrows_check_ = nullptr;
  QComboBox* zoom_box_ = nullptr;
  QCheckBox* scene_check_ = nullptr;
  QLabel* status_input_ = nullptr;
  QLabel* status_loop_ = nullptr;
  QLabel* status_activity_ = nullptr;
  // Write tab.
  QLabel* world_label_ = nullptr;
  // Record tab (the take it records is its own).
  RecordTab* record_tab_ = nullptr;
  // Train tab (the reference and the mode are its own).
  TrainTab* train_tab_ = nullptr;
  // Study tab (the study session it runs is its own).
  StudyTab* study_tab_ = nullptr;
  // Review tab (the study database it reviews is its own).
  ReviewTab* review_ = nullptr;
  // Mentor tab (it has the device and the hand while a session runs: Activity::kMentoring).
  MentorTab* mentor_ = nullptr;
  // Learners tab (the practice folder and the plan picked are its own).
  LearnersTab* learners_tab_ = nullptr;
};

}  // namespace hattr::studio
