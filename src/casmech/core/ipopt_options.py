"""The IPOPT options an `ocp:` block (`solver:`) and `casmech optimize --option KEY=VALUE` may
set: an allow-list with each option's type and range, checked by casmech.core.option_values
(unknown key with a did-you-mean E101, wrong type E102, out of range E409).

The defaults are those casmech solves with when nothing is written (IPOPT's own where casmech
sets none); only the keys written are passed to IPOPT (as `ipopt.<key>`), so settings a
transcription makes for itself (a limited-memory Hessian where only first derivatives exist)
stay unless written.
"""

from __future__ import annotations

from casmech.core.option_values import option
from casmech.core.records import record

YES_NO = ("yes", "no")


@record
class IpoptOptions:
    max_iter: int = option(500, "largest number of IPOPT iterations", low=0, high=100_000)
    tol: float = option(1e-10, "IPOPT's relative convergence tolerance", low=0, high=1,
                        open_low=True)
    acceptable_tol: float = option(1e-6, "the 'acceptable' tolerance IPOPT stops at after "
                                   "acceptable_iter iterations", low=0, open_low=True)
    acceptable_iter: int = option(15, "iterations at the acceptable level before stopping "
                                  "(0: off)", low=0, high=100_000)
    constr_viol_tol: float = option(1e-4, "absolute tolerance on the constraint violation",
                                    low=0, open_low=True)
    dual_inf_tol: float = option(1.0, "absolute tolerance on the dual infeasibility", low=0,
                                 open_low=True)
    print_level: int = option(0, "IPOPT's output (0 silent .. 12); --verbose gives 5", low=0,
                              high=12)
    mu_init: float = option(0.1, "the barrier parameter's first value (small: a warm start "
                            "from a near-optimal guess)", low=0, open_low=True)
    mu_strategy: str = option("monotone", "the barrier parameter's update",
                              choices=("monotone", "adaptive"))
    warm_start_init_point: str = option("no", "start from the guess without pushing it "
                                        "inside the bounds", choices=YES_NO)
    bound_push: float = option(1e-2, "how far the guess is pushed inside its bounds", low=0,
                               open_low=True)
    bound_frac: float = option(1e-2, "the same, relative to the bounds' gap", low=0, high=0.5,
                               open_low=True)
    hessian_approximation: str = option("exact", "the Hessian: exact (second derivatives by "
                                        "CasADi) or limited-memory (L-BFGS)",
                                        choices=("exact", "limited-memory"))
    nlp_scaling_method: str = option("gradient-based", "scaling of the problem",
                                     choices=("gradient-based", "none"))
    max_cpu_time: float = option(1e6, "largest CPU time of the solve [s]", unit="s", low=0,
                                 open_low=True)
    mumps_pivtol: float = option(1e-4, "MUMPS's pivot tolerance (docs/optimal.md)", low=0,
                                 high=1)


def settings(written) -> dict:
    """CasADi's nlpsol settings (`ipopt.<key>`) of the written (key, value) pairs."""
    return {f"ipopt.{key}": value for key, value in written}
