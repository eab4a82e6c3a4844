"""
A humanoid's heel strike, from its URDF
=======================================

The paper's energy split holds for any mechanism: here the humanoid TALOS (PAL Robotics; its
URDF shipped offline by the ``example-robot-data`` package) is loaded through Pinocchio
(:func:`heelstrike.robots.load_robot`), placed in a gait-like pre-impact state
(:func:`heelstrike.robots.gait_state`: trailing sole at rest, leading sole descending at
0.3 m/s, base moving forward at 0.5 m/s), and its left sole strikes the ground flat, inert and
without slip (:func:`heelstrike.robots.robot_impact`). Then the paper's Figs. 2-3 for the robot:
``T_c`` and ``T_a`` over step length and strike speed
(:func:`heelstrike.robots.robot_heel_strike_study`, drawn by
:func:`heelstrike.plots.robots.plot_robot_study`). Needs the
``robots`` extra (``pip install '.[robots]'`` in a clone of heelstrike).
"""

from pathlib import Path

import numpy as np

from heelstrike.plots.robots import plot_robot_study
from heelstrike.robots import (
    ContactSpec,
    gait_state,
    load_robot,
    robot_heel_strike_study,
    robot_impact,
)

robot = load_robot("talos")
print(f"{robot.name}: {robot.nv} velocity coordinates, {robot.mass:.1f} kg, "
      f"from {Path(robot.source).name}")
left, right = robot.feet
q, v = gait_state(robot, step_length=0.3, strike_speed=0.3)
hit = robot_impact(robot, q, v, strike=[ContactSpec(frame=left, kind="flat")])
d = hit.to_dict()
print(f"T = {d['T']:.3f} J = T_c {d['T_c']:.3f} J (lost) + T_a {d['T_a']:.3f} J (kept)")

# %%
# Over a grid of step lengths and strike speeds, in one batched call of the impact algebra.
study = robot_heel_strike_study(robot, np.linspace(0.05, 0.5, 10), np.linspace(0.1, 0.5, 5))
fig = plot_robot_study(study)
fig.savefig("talos_heel_strike.png")
