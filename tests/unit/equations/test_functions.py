"""The interpreted bundle (equations/functions.py): its functions built on first use."""

import numpy as np

import casmech
from casmech.equations import bodies, derivatives, rows
from casmech.equations.functions import all_sx, build_functions
from casmech.model.lower import lower
from tests.conftest import MODELS

NAMES = ("phi", "phi_q", "nu", "gamma", "variations", "phi_scaled", "mass_matrix",
         "generalized_forces", "energy", "reactions", "body_rates", "element_outputs")


def test_reading_one_function_builds_no_other(monkeypatch):
    """An analysis that reads phi does not pay for the mass matrix or the r-omega functions;
    phi, phi_q, nu and gamma share one build of the rows."""
    calls = {"mass_matrix": 0, "romega_mass": 0, "constraints": 0}
    for module, name in ((bodies, "mass_matrix"), (bodies, "romega_mass"),
                         (rows, "constraints")):
        original = getattr(module, name)

        def counted(*args, original=original, name=name, **kwargs):
            calls[name] += 1
            return original(*args, **kwargs)
        monkeypatch.setattr(module, name, counted)
    bundle = build_functions(lower(casmech.load(MODELS / "four_bar.yaml")))
    bundle["phi"]
    bundle["phi_q"]
    assert "mass_matrix" in bundle.functions and "nothing" not in bundle.functions
    assert calls == {"mass_matrix": 0, "romega_mass": 0, "constraints": 1}
    assert all_sx(bundle.functions) and calls == {"mass_matrix": 0, "romega_mass": 0,
                                                  "constraints": 1}
    bundle["romega_mass"], bundle["mass_matrix"], bundle["mass_matrix"], bundle["gamma"]
    assert calls == {"mass_matrix": 1, "romega_mass": 1, "constraints": 1}


def test_the_bundle_lists_every_function_in_order_and_each_equals_a_fresh_build():
    """Listing the names builds what is needed to know them; each function, built alone in a
    bundle of its own, equals the one built alongside the others (the same graph)."""
    ir = lower(casmech.load(MODELS / "slider_crank.yaml"))
    whole = build_functions(ir)
    names = list(whole.functions)
    assert tuple(names[:len(NAMES)]) == NAMES
    assert names[len(NAMES):] and all(n.startswith("romega_") for n in names[len(NAMES):])
    rng = np.random.default_rng(2)
    for name in names:
        alone = build_functions(ir)[name]
        together = whole[name]
        assert alone.name_in() == together.name_in()
        args = [rng.uniform(-1, 1, together.sparsity_in(k).shape)
                for k in range(together.n_in())]
        for a, b in zip(alone.call(args), together.call(args), strict=True):
            # the same SX graph evaluated on the same numbers: bitwise equal
            np.testing.assert_allclose(np.array(a), np.array(b), rtol=0, atol=0)


def test_a_function_set_by_a_caller_is_kept_and_listed_last():
    """codegen adds prescribed_step to an interpreted bundle: it is listed after the bundle's
    own, survives the build of the group it would shadow, and all_sx sees its kind."""
    import casadi as ca

    bundle = build_functions(lower(casmech.load(MODELS / "four_bar.yaml")))
    x = ca.MX.sym("x")
    step = ca.Function("prescribed_step", [x], [2 * x])
    bundle.functions["prescribed_step"] = step
    names = list(bundle.functions)
    assert names[-1] == "prescribed_step" and len(names) == len(set(names))
    assert bundle["prescribed_step"] is step and not all_sx(bundle.functions)
    romega_mass = bundle["romega_mass"]
    bundle.functions["romega_mass"] = step  # replaces a built one
    assert bundle["romega_mass"] is step and romega_mass is not step
    del bundle.functions["prescribed_step"], bundle.functions["romega_mass"]
    assert "prescribed_step" not in bundle.functions and all_sx(bundle.functions)
    assert "romega_mass" not in list(bundle.functions)


def test_a_first_read_of_a_function_whose_name_needs_its_group_keeps_the_listing():
    """Reading romega_mass first (its group's names are known only once built) leaves every
    name listed, as after listing first."""
    ir = lower(casmech.load(MODELS / "four_bar.yaml"))
    fresh, listed = build_functions(ir), build_functions(ir)
    expected = list(listed.functions)
    fresh["romega_mass"]
    assert list(fresh.functions) == expected and len(fresh.functions) == len(expected)


def test_phi_and_nu_alone_take_no_second_derivative_and_phi_q_matches_differences(monkeypatch):
    """A joint-coordinate run reads phi and nu (assembly) but never phi_q or gamma: those
    derivatives of the whole phi are taken only when read, and then agree with central
    differences of phi."""
    derived = []
    original = derivatives.Derived._derive

    def counted(self, key):
        derived.append(key)
        return original(self, key)
    monkeypatch.setattr(derivatives.Derived, "_derive", counted)
    bundle = build_functions(lower(casmech.load(MODELS / "four_bar.yaml")))
    bundle["phi"], bundle["nu"], bundle["reactions"]
    assert derived == ["nu"]
    phi, phi_q = bundle["phi"], bundle["phi_q"]
    assert derived == ["nu", "phi_q"]
    q = np.random.default_rng(5).uniform(-1, 1, phi_q.size1_in(1))
    step = 1e-6
    columns = [(np.array(phi(0.3, q + step * e)) - np.array(phi(0.3, q - step * e))).ravel()
               / (2 * step) for e in np.eye(q.size)]
    # central differences of a smooth phi at step 1e-6: truncation ~1e-12, round-off ~1e-10
    np.testing.assert_allclose(np.array(phi_q(0.3, q)), np.array(columns).T, rtol=0,
                               atol=1e-7)
    bundle["gamma"]
    assert derived == ["nu", "phi_q", "gamma"]
