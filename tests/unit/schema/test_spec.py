"""The pydantic mirror of the format: accepted shapes, translated errors, JSON Schema."""

import json

import jsonschema
import pytest
import yaml

from casmech.schema import export, spec, spec_errors
from casmech.schema.loader import load_document
from tests.conftest import MODELS

HEADER = "casmech: 1\nname: s\n"
BAR = "  - {name: bar, mass: 1, inertia: [1, 1, 1], position: [0, 0, 0]}\n"


def validate(text: str):
    return spec_errors.validate(load_document(HEADER + text, "s.yaml"))


def errors(text: str) -> list[tuple]:
    model, found = validate(text)
    assert model is None
    return [(d.code, d.path, d.source.line, d.source.col) for d in found]


def only(text: str):
    model, found = validate(text)
    assert len(found) == 1, found
    return found[0]


def test_every_joint_and_force_type_is_discriminated():
    joints = "".join(
        f"  - {{name: j{k}, type: {cls.model_fields['type'].annotation.__args__[0]}, {keys}}}\n"
        for k, (cls, keys) in enumerate(
            [
                (spec.Revolute, "at: [0,0,0], axis: [0,0,1]"),
                (spec.Spherical, "at: [0,0,0]"),
                (spec.Universal, "at: [0,0,0], axis_i: [1,0,0], axis_j: [0,1,0]"),
                (spec.Cylindrical, "at: [0,0,0], axis: [0,0,1]"),
                (spec.Translational, "at: [0,0,0], axis: [0,0,1]"),
                (spec.Fixed, "at: [0,0,0]"),
                (spec.Distance, "at_i: [0,0,0], at_j: [1,0,0]"),
                (spec.RevoluteSpherical, "at: [0,0,0], axis: [0,0,1], at_j: [1,0,0]"),
                (spec.Planar, "at: [0,0,0], axis: [0,0,1]"),
                (spec.DP1, "a_i: [1,0,0], a_j: [0,1,0]"),
                (spec.DP2, "a_i: [1,0,0], s_i: [0,0,0], s_j: [0,1,0]"),
                (spec.D, "s_i: [0,0,0], s_j: [0,1,0], f: 4"),
                (spec.CD, "c: [1,0,0], s_i: [0,0,0], s_j: [0,1,0]"),
            ]
        )
    )
    joints = joints.replace("}\n", ", body_i: ground, body_j: bar}\n")
    forces = (
        "  - {name: k, type: tsda, body_i: ground, at_i: [0,0,0], body_j: bar, at_j: [1,0,0]}\n"
        "  - {name: r, type: rsda, joint: j0}\n"
        "  - {name: f, type: force, body: bar, value: [0, 0, t]}\n"
        "  - {name: q, type: torque, body: bar, value: [0, 0, 1], frame: body}\n"
    )
    model, found = validate(f"bodies:\n{BAR}joints:\n{joints}forces:\n{forces}")
    assert found == []
    assert [type(j).__name__ for j in model.joints] == [
        "Revolute", "Spherical", "Universal", "Cylindrical", "Translational", "Fixed",
        "Distance", "RevoluteSpherical", "Planar", "DP1", "DP2", "D", "CD",
    ]  # fmt: skip
    assert [type(f).__name__ for f in model.forces] == ["TSDA", "RSDA", "PointForce", "Torque"]
    assert model.joints[9].f == "0" and model.joints[11].f == 4
    assert (model.forces[0].stiffness, model.forces[0].actuator) == (0, "0")
    assert (model.forces[2].frame, model.forces[3].frame) == ("global", "body")


@pytest.mark.parametrize("empty", ["", "parameters:\njoints:\nforces:\nanalysis:\ndescription:\n"])
def test_defaults(empty):
    model, _ = validate(f"bodies:\n{BAR}{empty}")
    assert model.gravity == (0, 0, -9.81)
    assert (model.joints, model.forces, model.parameters, model.description) == ((), (), {}, "")
    assert model.analysis == spec.Analysis(type="dynamics", formulation="auto")


def test_a_required_key_without_value_is_a_wrong_type():
    diagnostic = only("bodies:\n  - {name: b, mass: , inertia: [1, 1, 1], position: [0, 0, 0]}\n")
    assert (diagnostic.code, diagnostic.path, diagnostic.got) == (
        "E102", "bodies[0].mass", "nothing (null)",
    )  # fmt: skip


@pytest.mark.parametrize(
    "inertia", ["[1, 2, 2]", "[1, 2, 2, 0.1, 0, 0]", "[[1, 0, 0], [0, 2, 0], [0, 0, 2]]"]
)
def test_inertia_shapes(inertia):
    model, found = validate(
        f"bodies:\n  - {{name: b, mass: 1, inertia: {inertia}, position: [0, 0, 0]}}\n"
    )
    assert found == []


@pytest.mark.parametrize(
    "item",
    [
        "{box: [1, 2, 3]}",
        "{cylinder: {radius: 1, length: 2}, offset: [0, 0, 1]}",
        "{sphere: r, orientation: {axis_angle: {axis: [0, 0, 1], angle: 1}}}",
        "{mesh: part.stl, scale: 0.001}",
    ],
)
def test_geometry_items(item):
    model, found = validate(f"bodies:\n{BAR[:-2]}, geometry: [{item}]}}\n")
    assert found == []


def test_locations_drop_union_tags():
    text = (
        f"bodies:\n{BAR}joints:\n"
        "  - {name: a, type: spherical, body_i: ground, body_j: bar, at: [0, 0, 0]}\n"
        "  - {name: b, type: revolute, body_i: ground, body_j: bar, at: [0, 0, 0]}\n"
        "  - {name: c, type: universal, body_i: ground, body_j: bar, at: [0, 0, 0],\n"
        "     axis_i: [1, 0, x, 4], axis_j: [0, 1, true]}\n"
    )
    assert errors(text) == [
        ("E100", "joints[1].axis", 7, 5),  # at the joint's mapping
        ("E102", "joints[2].axis_i", 9, 14),
        ("E102", "joints[2].axis_j[2]", 9, 43),
    ]


def test_unknown_key_hint_lists_the_keys_of_the_right_type():
    text = (
        f"bodies:\n{BAR}joints:\n"
        "  - {name: a, type: universal, body_i: ground, body_j: bar, at: [0, 0, 0],\n"
        "     axis_i: [1, 0, 0], axis_j: [0, 1, 0], axis_ii: [0, 0, 1]}\n"
    )
    model, found = validate(text)
    [diagnostic] = found
    assert (diagnostic.code, diagnostic.path, diagnostic.source.col) == (
        "E101",
        "joints[0].axis_ii",
        44,
    )
    assert diagnostic.hint == "did you mean 'axis_i'?"
    diagnostic = only(f"bodies:\n{BAR}zzz: 1\n")
    assert diagnostic.hint.startswith("allowed keys: casmech, name, description, parameters")


def test_wrong_types_say_expected_and_got():
    diagnostic = only(
        "bodies:\n  - {name: b, mass: true, inertia: [1, 1, 1], position: [0, 0, 0]}\n"
    )
    assert (diagnostic.path, diagnostic.expected, diagnostic.got) == (
        "bodies[0].mass", "a number or an expression string", "true",
    )  # fmt: skip
    diagnostic = only("bodies: {name: b}\n")
    assert (diagnostic.code, diagnostic.expected, diagnostic.got) == ("E102", "a list", "a mapping")
    diagnostic = only(
        "bodies:\n  - {name: b, mass: 1, inertia: [1, 1, 1, 1], position: [0, 0, 0]}\n"
    )
    assert (diagnostic.expected, diagnostic.got) == ("a list of 3 items", "a list of 4 items")
    assert "3x3" in diagnostic.hint


def test_enums_tags_and_versions():
    found = {d.path: d for d in validate(
        f"bodies:\n{BAR}joints:\n  - {{name: j, body_i: ground, body_j: bar}}\n"
        "  - {name: k, type: sphrical, body_i: ground, body_j: bar, at: [0, 0, 0]}\n"
        "analysis: {formulation: romga}\n"
    )[1]}  # fmt: skip
    assert found["joints[0].type"].code == "E100"
    assert found["joints[1].type"].hint == "did you mean 'spherical'?"
    assert found["analysis.formulation"].expected == "rp | romega | joint | auto"
    for version, got in [("1.0", "1.0"), ("true", "true"), ("'1'", "'1'"), ("2", "2")]:
        document = load_document(f"casmech: {version}\nname: s\nbodies: []\n")
        [diagnostic] = spec_errors.validate(document)[1]
        assert (diagnostic.code, diagnostic.expected, diagnostic.got) == ("E104", "1", got)


def test_geometry_kind_errors():
    def geometry(item):
        return only(f"bodies:\n{BAR[:-2]}, geometry: [{item}]}}\n")

    assert (geometry("{boxx: [1, 1, 1]}").code, geometry("{boxx: [1, 1, 1]}").hint) == (
        "E100", "did you mean 'box'?",
    )  # fmt: skip
    assert geometry("{box: [1, 1, 1], sphere: 1}").code == "E410"
    assert geometry("{box: [1, 1, 1], scale: 2}").code == "E101"
    assert geometry("[1, 2]").code == "E102"


def test_committed_json_schema_is_current():
    assert export.DEFAULT_PATH.read_text(encoding="utf-8") == export.schema_text()


def test_json_schema_accepts_a_model(tmp_path, schema_validator):
    schema = json.loads(export.schema_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    model = {"casmech": 1, "name": "s", "bodies": [{"name": "b", "mass": "m",
             "inertia": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "position": [0, 0, 0]}]}  # fmt: skip
    # what jsonschema.validate does, with the schema checked once (schema_validator)
    schema_validator.validate(model)
    with pytest.raises(jsonschema.ValidationError):
        schema_validator.validate({**model, "gravty": [0, 0, 0]})
    assert export.main([str(tmp_path / "s.json")]) == 0
    assert (tmp_path / "s.json").read_text(encoding="utf-8") == export.schema_text()


@pytest.fixture(scope="module")
def schema_validator():
    """The validator jsonschema.validate picks for the exported schema, the schema checked
    once: building the schema and the validator is the cost, not validating a model."""
    schema = json.loads(export.schema_text())
    validator = jsonschema.validators.validator_for(schema)
    validator.check_schema(schema)
    return validator(schema)


@pytest.mark.parametrize("model", sorted(MODELS.glob("*.yaml")), ids=lambda p: p.name)
def test_json_schema_accepts_every_example_model(model, schema_validator):
    """What an editor's YAML plug-in checks must agree with casmech on the shipped models."""
    schema_validator.validate(yaml.safe_load(model.read_text()))


def test_unknown_key_hint_uses_the_key_as_written_not_the_python_field():
    # Repeat's `from` is the pydantic field `from_` (a Python keyword); the hint must say 'from'
    text = (
        "bodies:\n  - {name: b, mass: 1, inertia: [1, 1, 1], position: [0, 0, 0],\n"
        "     repeat: {index: i, form: 1, to: 2}}\n"
    )
    model, found = validate(text)
    unknown = [d for d in found if d.code == "E101"]
    assert [d.path for d in unknown] == ["bodies[0].repeat.form"]
    assert unknown[0].hint == "did you mean 'from'?"


def test_the_formats_classes_hold_their_annotations_as_objects():
    """No class of the format's modules has a string annotation (none of them imports
    `from __future__ import annotations`): pydantic would evaluate each string when it makes
    the class (docs/decisions/pydantic-defer-build.md)."""
    from casmech.core import spec_base, spec_items
    from casmech.elements.forces import specs
    from casmech.schema import (
        spec_analysis,
        spec_bodies,
        spec_components,
        spec_events,
        spec_forces,
        spec_joint_blocks,
        spec_joints,
        spec_problems,
        spec_shapes,
    )

    modules = (spec_base, spec_items, spec, spec_analysis, spec_bodies, spec_components,
               spec_events, spec_forces, spec_joint_blocks, spec_joints, spec_problems,
               spec_shapes, specs)
    classes = [cls for module in modules for cls in vars(module).values()
               if isinstance(cls, type) and cls.__module__ == module.__name__]
    assert len(classes) > 30  # (the format's classes made at import)
    written = [f"{cls.__module__}.{cls.__qualname__}.{key}" for cls in classes
               for key, value in vars(cls).get("__annotations__", {}).items()
               if isinstance(value, str)]
    assert written == []
