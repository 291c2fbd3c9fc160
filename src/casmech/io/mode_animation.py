"""A mode shape as a results table that `casmech animate --mode N` draws.

A modal run writes linear_model.npz (runtime.modal): the equilibrium q*, the null-space basis N
(dq = N z) and each mode's vector v in z, scaled so that its body motions' largest entry is 1
(metres or radians). Frame k shows

    q(phi_k) = q* + amplitude * N Re(v e^(i phi_k)),   phi_k = 2 pi f t_k,

with each body's Euler parameters normalized, so that the bodies stay rigid; the motion is the
undamped shape (damping shows in modes.csv, not in the picture). f is the mode's damped
frequency; a mode that does not oscillate (a real eigenvalue, a zero-stiffness DOF) is played
back and forth at 1 Hz. To first order in the amplitude the frames satisfy the constraints.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from casmech.errors import UsageError
from casmech.io.animate import POSE

FRAMES_PER_CYCLE = 48
STILL_FREQUENCY_HZ = 1.0  # playback rate of a mode that does not oscillate


def read_linear_model(path: Path) -> dict[str, np.ndarray]:
    """The arrays of a modal run's linear_model.npz."""
    if not path.is_file():
        raise UsageError(f"{path}: no such file (hint: `--mode` animates a modal run's modes: "
                         "`casmech run MODEL --analysis modal` writes linear_model.npz beside "
                         "its results.csv)")
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: data[name] for name in data.files}
    except (OSError, ValueError) as error:
        raise UsageError(f"{path}: not a linear model written by casmech ({error})") from None
    needed = ("q_equilibrium", "basis", "eigenvalues", "mode_vectors")
    missing = [name for name in needed if name not in arrays or arrays[name].ndim == 0]
    if missing:
        raise UsageError(f"{path}: no {', '.join(missing)} (hint: run the modal analysis again "
                         "with this casmech version)")
    return arrays


def mode_table(linear: dict[str, np.ndarray], bodies: tuple[str, ...], mode: int,
               amplitude: float, cycles: float = 2.0) -> tuple[list[str], np.ndarray]:
    """(names, values): t and every body's x, y, z, e0..e3 over `cycles` periods of mode `mode`
    (numbered from 1 as in modes.csv)."""
    count = len(linear["eigenvalues"])
    if not 1 <= mode <= count:
        raise UsageError(f"--mode {mode}: the model has {count} mode"
                         f"{'' if count == 1 else 's'} (hint: numbered 1..{count} in modes.csv)")
    if not (np.isfinite(amplitude) and amplitude > 0) or not (np.isfinite(cycles) and cycles > 0):
        raise UsageError("--amplitude and --cycles must be positive numbers")
    q_star, basis = linear["q_equilibrium"], linear["basis"]
    nb = len(bodies)
    if q_star.size != 7 * nb:
        raise UsageError(f"the linear model has {q_star.size // 7} bodies, the model {nb} "
                         "(hint: animate the model the modal run was made from)")
    eigenvalue, vector = linear["eigenvalues"][mode - 1], linear["mode_vectors"][:, mode - 1]
    frequency = abs(eigenvalue.imag) / (2 * np.pi) or STILL_FREQUENCY_HZ
    frames = int(np.ceil(cycles * FRAMES_PER_CYCLE)) + 1
    t = np.linspace(0.0, cycles / frequency, frames)
    motion = np.real(np.outer(basis @ vector, np.exp(2j * np.pi * frequency * t)))
    q = q_star[:, None] + amplitude * motion  # (7 nb, frames)
    r = q[:3 * nb].T.reshape(frames, nb, 3)
    p = q[3 * nb:].T.reshape(frames, nb, 4)
    p = p / np.linalg.norm(p, axis=2, keepdims=True)
    names = ["t"] + [f"{body}.{c}" for body in bodies for c in POSE]
    return names, np.column_stack([t, np.concatenate([r, p], axis=2).reshape(frames, 7 * nb)])
