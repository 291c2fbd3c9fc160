"""A URDF joint's `dynamics friction`, imported as the joint's Coulomb friction, against the
closed form of a disc spinning about the vertical (gravity exerts no torque about its axis):
it slows at f / I until it stops at t* = I w0 / f, then stays stuck."""

import numpy as np

import casmech
from casmech.importers.emit import to_yaml
from casmech.importers.urdf import import_urdf

INERTIA, FRICTION, RATE = 0.5, 0.3, 1.2  # kg m^2 about the axis, N m, rad/s at t = 0
TURNTABLE = f"""<?xml version="1.0"?>
<robot name="turntable">
  <link name="base"/>
  <joint name="spin" type="continuous">
    <parent link="base"/>
    <child link="disc"/>
    <origin xyz="0 0 0.1"/>
    <axis xyz="0 0 1"/>
    <dynamics friction="{FRICTION}"/>
  </joint>
  <link name="disc">
    <inertial>
      <mass value="2"/>
      <inertia ixx="0.3" ixy="0" ixz="0" iyy="0.3" iyz="0" izz="{INERTIA}"/>
    </inertial>
  </link>
</robot>
"""


def test_urdf_friction_stops_a_spinning_disc_as_coulomb_friction_does(tmp_path):
    path = tmp_path / "turntable.urdf"
    path.write_text(TURNTABLE)
    model = casmech.loads(to_yaml(import_urdf(path, velocities={"spin": RATE})),
                          file=str(tmp_path / "turntable.yaml"))
    functions = casmech.compile(model)
    result = casmech.analyze(functions, "dynamics", t_end=3.0, output_step=0.01, rtol=1e-10,
                             atol=1e-12)
    names, values = casmech.results_table(functions, result)
    column = dict(zip(names, values.T, strict=True))
    t, stop = column["t"], INERTIA * RATE / FRICTION
    sliding = t < stop
    angle = np.where(sliding, RATE * t - FRICTION * t**2 / (2 * INERTIA),
                     INERTIA * RATE**2 / (2 * FRICTION))
    rate = np.where(sliding, RATE - FRICTION * t / INERTIA, 0.0)
    # integrator tolerance 1e-10 over 3 s of a piecewise-quadratic angle
    np.testing.assert_allclose(column["spin.angle"], angle, rtol=0, atol=1e-9)
    np.testing.assert_allclose(column["spin.angle_dot"], rate, rtol=0, atol=1e-9)
    # the law while sliding is -f (rate > 0); stuck, it holds nothing (no torque about z)
    np.testing.assert_allclose(column["spin.friction"][sliding], -FRICTION, rtol=0, atol=1e-12)
    np.testing.assert_allclose(column["spin.friction"][~sliding], 0.0, rtol=0, atol=1e-9)
    (switch,) = result.metadata["friction_switches"]
    assert switch["joint"] == "spin" and switch["mode"] == 0
    # the stop is located to the event tolerance
    np.testing.assert_allclose(switch["t"], stop, rtol=0, atol=1e-9)
