"""runtime.kinematics' output grid: output_times against its definition (multiples of the step
from t0, t_end itself where the last one falls short by more than 1e-9 of a step), and
output_count against the grid's length."""

import numpy as np

from casmech.runtime.kinematics import output_count, output_times


def test_the_grid_is_the_steps_from_t0_then_t_end_and_its_count_is_its_length():
    rng = np.random.default_rng(36)
    grids = [(0.0, 1.0, 0.01), (0.0, 1.0, 0.3), (0.5, 0.5, 0.1), (0.1, 0.35, 0.1),
             (0.0, 10.0, 1e-3), (0.3, 1.7, 0.013)]
    grids += [(float(t0), float(t0 + span), float(step)) for t0, span, step in zip(
        rng.uniform(0, 3, 400), rng.uniform(0, 5, 400), rng.uniform(1e-3, 1, 400),
        strict=True)]
    for t0, t_end, step in grids:
        times = output_times(t0, t_end, step)
        assert output_count(t0, t_end, step) == len(times), (t0, t_end, step)
        k = np.arange(len(times))
        steps = np.isclose(times, t0 + step * k, rtol=0, atol=1e-12 * max(1.0, t_end))
        # every point a multiple of the step from t0, the last possibly t_end itself
        assert steps[:-1].all() and (steps[-1] or times[-1] == t_end), (t0, t_end, step)
        assert times[-1] >= t_end - 1e-9 * step  # the grid reaches t_end ...
        assert times[-1] <= t_end + 1e-9 * step + 1e-12 * max(1.0, t_end)  # ... not beyond
        assert len(times) == 1 or times[-2] < t_end - 1e-9 * step  # and stops there
