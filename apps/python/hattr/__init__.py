"""hattr: motor skill training with haptic attributes, from Python.

Haptic profiles (position, velocity and force at the servo rate) as NumPy arrays, the
paper's analysis (preprocessing, DTW, its trial scores, balanced two-way ANOVA and Tukey
HSD), study databases, and trials on the simulated pen. SI units throughout: metres,
seconds, newtons; names carry them (``t_s``, ``p_WT_m``, ``f_user_W_N``).

Errors in what you pass (a file, an argument, a study) raise :class:`hattr.InputError`,
a :class:`ValueError`, with the same message the ``hattr`` command prints. A walk-through
is in docs/python.md.
"""

from ._hattr import *  # noqa: F401,F403  (the extension defines __all__'s names)
from ._hattr import __version__  # noqa: F401

__all__ = [
    "Error", "InputError",
    "HapticProfile", "read_profile", "write_profile", "import_svc2004", "import_susig",
    "normalize", "time_scale", "interpolate_at", "preprocess_trial",
    "dtw", "dtw_with_path", "dtw_batch", "dtw_cost_matrix", "dtw_simd_target",
    "TrialScorer", "AnovaTable", "TukeyResult", "two_way_anova", "tukey_hsd", "describe_groups",
    "lmm", "compare_lmm", "kinematics", "fit_learning_curve",
    "Study", "create_study", "run_study",
    "run_trial", "strategies", "simulate_study", "power_analysis",
    "servo_check", "check_device",
    "Library",
]
