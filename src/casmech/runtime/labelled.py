"""Sensitivities and linear models as labelled pandas DataFrames; the arrays they are made
from stay on their objects (optimal.sensitivity.Sensitivity, runtime.modal.LinearModel).

- sensitivities: one row per (t, output) (a MultiIndex), the column `value` and one column
  `d/d<parameter>` per parameter; `frame["d/dm"].unstack("output")` is a time by output table;
- a linear model's matrices A, B, C, D with the state, input and output names as index and
  columns; its modes (index `mode` from 1) and mode shapes (columns `<body>.<dx..rz>`,
  complex, each mode scaled so that its largest entry is 1).

The sensitivity and modes frames carry `attrs["units"]` (output or column -> SI unit, as the
results contract's). pandas is imported when a frame is made.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from casmech.core.columns import units

if TYPE_CHECKING:
    import pandas as pd

INTEGRAL = "integral("  # an output integrated from t0: its unit times s


def _unit(output: str) -> str:
    if output.startswith(INTEGRAL) and output.endswith(")"):
        inner = units([output[len(INTEGRAL):-1]])[output[len(INTEGRAL):-1]]
        return "s" if inner == "-" else f"{inner} s"
    return units([output])[output]


def sensitivity_frame(parameters: Sequence[str], outputs: Sequence[str], times: np.ndarray,
                      values: np.ndarray, jacobian: np.ndarray, mode: str) -> pd.DataFrame:
    """values (times, outputs) and jacobian (times, outputs, parameters) as one frame."""
    import pandas as pd

    index = pd.MultiIndex.from_product([np.asarray(times, float), list(outputs)],
                                       names=["t", "output"])
    columns = {"value": np.asarray(values, float).reshape(-1)}
    columns |= {f"d/d{name}": np.asarray(jacobian, float)[:, :, k].reshape(-1)
                for k, name in enumerate(parameters)}
    frame = pd.DataFrame(columns, index=index)
    frame.attrs.update(units={output: _unit(output) for output in outputs},
                       parameters=list(parameters), mode=mode)
    return frame


def matrix_frames(model) -> dict[str, pd.DataFrame]:
    """A, B, C, D of a LinearModel, labelled by its state, input and output names."""
    import pandas as pd

    axes = {"A": (model.state_names, model.state_names),
            "B": (model.state_names, model.input_names),
            "C": (model.output_names, model.state_names),
            "D": (model.output_names, model.input_names)}
    frames = {}
    for name, (rows, columns) in axes.items():
        matrix = np.asarray(getattr(model, name), float).reshape(len(rows), len(columns))
        frames[name] = pd.DataFrame(matrix, index=pd.Index(list(rows), name="row"),
                                    columns=pd.Index(list(columns), name="column"))
        frames[name].attrs["linearized_at"] = model.linearized_at
    return frames


def modes_frame(model) -> pd.DataFrame:
    """The modes table (modes.csv's columns), indexed by mode number."""
    import pandas as pd

    names, values = model.modes_table()
    frame = pd.DataFrame(values[:, 1:], columns=names[1:],
                         index=pd.Index(values[:, 0].astype(int), name=names[0]))
    frame.attrs["units"] = {"frequency_hz": "Hz", "damping_ratio": "-",
                            "eigenvalue_real": "1/s", "eigenvalue_imag": "1/s",
                            "damped_frequency_hz": "Hz"}
    frame.attrs["linearized_at"] = model.linearized_at
    return frame


def mode_shapes_frame(model, motions: Sequence[str]) -> pd.DataFrame:
    """The mode shapes (complex, the largest entry of each 1), a row per mode, a column per
    body motion `<body>.<motion>`."""
    import pandas as pd

    shapes = np.asarray(model.mode_shapes).reshape(len(model.eigenvalues), -1)
    columns = [f"{body}.{motion}" for body in model.body_names for motion in motions]
    return pd.DataFrame(shapes, columns=columns,
                        index=pd.Index(np.arange(1, shapes.shape[0] + 1), name="mode"))
