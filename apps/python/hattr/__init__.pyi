# Type stubs of the hattr package (the extension hattr._hattr). Units are in the names and
# docstrings: seconds, metres, newtons.
import os
from typing import Any, Iterable, Sequence, TypedDict

import numpy as np
import numpy.typing as npt

__version__: str

_Path = str | os.PathLike[str]
_Floats = npt.ArrayLike
_FloatArray = npt.NDArray[np.float64]

class Error(RuntimeError): ...
class InputError(Error, ValueError): ...

class HapticProfile:
    @staticmethod
    def from_arrays(t_s: _Floats, p_WT_m: _Floats, *, v_WT_m_per_s: _Floats | None = ...,
                    f_user_W_N: _Floats | None = ..., pen_down: npt.ArrayLike | None = ...,
                    metadata: dict[str, Any] | None = ...) -> HapticProfile: ...
    def __len__(self) -> int: ...
    def __eq__(self, other: object) -> bool: ...
    metadata: dict[str, Any]
    @property
    def raw_channels(self) -> dict[str, bool]: ...
    @property
    def duration_s(self) -> float: ...
    @property
    def measured_rate_hz(self) -> float: ...
    @property
    def pen_down_count(self) -> int: ...
    @property
    def channel_names(self) -> list[str]: ...
    def channel(self, name: str) -> _FloatArray: ...
    def channels(self) -> dict[str, _FloatArray]: ...
    @property
    def t_s(self) -> _FloatArray: ...
    @property
    def p_WT_m(self) -> _FloatArray: ...
    @property
    def v_WT_m_per_s(self) -> _FloatArray: ...
    @property
    def f_user_W_N(self) -> _FloatArray: ...
    @property
    def f_cmd_W_N(self) -> _FloatArray: ...
    @property
    def f_guide_W_N(self) -> _FloatArray: ...
    @property
    def pen_down(self) -> npt.NDArray[np.bool_]: ...
    @property
    def in_contact(self) -> npt.NDArray[np.bool_]: ...
    @property
    def writing_span_s(self) -> tuple[float, float]: ...

def read_profile(path: _Path) -> HapticProfile: ...
def write_profile(profile: HapticProfile, path: _Path, *, overwrite: bool = ...) -> None: ...
def import_svc2004(path: _Path, *, calibration: dict[str, Any] | _Path | None = ...) -> HapticProfile: ...
def import_susig(path: _Path, *, calibration: dict[str, Any] | _Path | None = ...) -> HapticProfile: ...

def normalize(values: _Floats, how: str = ...) -> _FloatArray: ...
def time_scale(trial_t_s: _Floats, expert_t_s: _Floats) -> _FloatArray: ...
def interpolate_at(t_s: _Floats, values: _Floats, at_t_s: _Floats) -> _FloatArray: ...
def preprocess_trial(trial_t_s: _Floats, trial_values: _Floats, expert_t_s: _Floats,
                     how: str = ...) -> _FloatArray: ...

def dtw(a: _Floats, b: _Floats, *, cost: str = ..., band_fraction: float | None = ...,
        abandon_above: float = ...) -> float: ...
def dtw_with_path(a: _Floats, b: _Floats, *, cost: str = ...,
                  band_fraction: float | None = ...) -> tuple[float, npt.NDArray[np.int64]]: ...
def dtw_batch(a: Sequence[_Floats], b: Sequence[_Floats], *, cost: str = ...,
              band_fraction: float | None = ..., abandon_above: float = ...) -> _FloatArray: ...
def dtw_cost_matrix(series: Sequence[_Floats], *, cost: str = ..., band_fraction: float | None = ...,
                    threads: int = ...) -> _FloatArray: ...
def dtw_simd_target() -> str: ...

class TrialScore(TypedDict):
    x: float
    y: float
    z: float
    fx: float
    fy: float
    fz: float
    shape: float
    force: float

class TrialScorer:
    def __init__(self, expert: HapticProfile, *, normalization: str = ..., cost: str = ...,
                 band_fraction: float | None = ...) -> None: ...
    def score(self, trial: HapticProfile) -> TrialScore: ...
    def score_all(self, trials: Sequence[HapticProfile], *, threads: int = ...) -> list[TrialScore]: ...
    @property
    def expert_samples(self) -> int: ...

class AnovaRow(TypedDict):
    source: str
    df: int
    sum_sq: float
    mean_sq: float
    f: float
    p: float
    partial_eta_sq: float
    error_term: str

class AnovaTable:
    @property
    def rows(self) -> list[AnovaRow]: ...
    def row(self, source: str) -> AnovaRow: ...
    @property
    def replicates(self) -> int: ...
    @property
    def a_levels(self) -> list[str]: ...
    @property
    def b_levels(self) -> list[str]: ...

class TukeyComparison(TypedDict):
    comparison: str
    level: str
    other_level: str
    diff: float
    lower: float
    upper: float
    p_adjusted: float

class TukeyResult:
    @property
    def factor(self) -> str: ...
    @property
    def confidence(self) -> float: ...
    @property
    def error_term(self) -> str: ...
    @property
    def error_mean_sq(self) -> float: ...
    @property
    def error_df(self) -> int: ...
    @property
    def comparisons(self) -> list[TukeyComparison]: ...

class GroupStats(TypedDict):
    a: str
    b: str
    count: int
    mean: float
    variance: float
    sd: float

def two_way_anova(a: Iterable[Any], b: Iterable[Any], y: _Floats, *, a_name: str = ..., b_name: str = ...,
                  b_random: bool = ...) -> AnovaTable: ...
def tukey_hsd(a: Iterable[Any], b: Iterable[Any], y: _Floats, *, factor: str = ..., a_name: str = ...,
              b_name: str = ..., b_random: bool = ..., confidence: float = ...) -> TukeyResult: ...
def describe_groups(a: Iterable[Any], b: Iterable[Any], y: _Floats, *, by: str = ...) -> list[GroupStats]: ...

class SubjectRecord(TypedDict):
    id: str
    position: int
    participant: str
    seed: int
    mode_order: list[str]
    options: Any

class TrialRecord(TypedDict):
    trial_id: int
    subject: str
    sequence: int
    mode: str
    phase: str
    trial: int
    status: str
    attempts: int
    interruptions: int
    started_utc: str
    ended_utc: str
    outcome: str
    sample_count: int
    disturbed: str
    disturbed_attempts: int

class Study:
    @staticmethod
    def open(path: _Path) -> Study: ...
    @property
    def path(self) -> os.PathLike[str]: ...
    @property
    def name(self) -> str: ...
    @property
    def skill(self) -> str: ...
    @property
    def schema_version(self) -> int: ...
    @property
    def definition(self) -> dict[str, Any]: ...
    def subjects(self) -> list[SubjectRecord]: ...
    def trials(self, subject: str | None = ...) -> list[TrialRecord]: ...
    def trial_profile(self, trial_id: int) -> HapticProfile: ...
    def expert(self, skill: str | None = ...) -> HapticProfile: ...
    def analyze(self, *, normalization: str = ..., cost: str = ..., band_fraction: float | None = ...,
                threads: int = ...) -> dict[str, Any]: ...
    def __enter__(self) -> Study: ...
    def __exit__(self, *args: object) -> bool: ...

def create_study(path: _Path, study: _Path | dict[str, Any], *, base_dir: _Path = ...) -> Study: ...
def run_study(path: _Path, *, subject: str | None = ..., max_trials: int | None = ...) -> int: ...

class TrialRun(TypedDict):
    profile: HapticProfile
    clamps: list[str]
    ticks: int
    missed_samples: int
    overruns: int
    faults: int
    link_faults: int
    stalls: int
    clock: str
    end_reason: str
    failure: str

def run_trial(hand: HapticProfile | _Path, reference: HapticProfile | _Path | None = ..., mode: str = ..., *,
              world: dict[str, Any] | _Path | None = ..., device: str = ..., rate_hz: float = ...,
              clock: str = ..., tail_s: float = ..., pen_up_end_s: float = ..., max_duration_s: float = ...,
              indexing: str = ..., speed: float = ..., subject: str = ..., skill: str = ...,
              trial: int = ...) -> TrialRun: ...

class SimulatedStudy(TypedDict):
    database: os.PathLike[str]
    report_html: os.PathLike[str] | None
    trials: int
    servo_ticks: int
    analysis: dict[str, Any]

def simulate_study(out_dir: _Path, *, subjects: int = ..., seed: int = ..., training_trials: int = ...,
                   recall_trials: int = ..., guidance: bool = ..., glyph: str = ...,
                   write_report: bool = ...) -> SimulatedStudy: ...
