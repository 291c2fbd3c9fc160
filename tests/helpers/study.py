"""Models of the study tests (closed forms in their comments) and a study runner."""

from pathlib import Path

HERE = Path(__file__).resolve().parent
PENDULUM = HERE / "study_models" / "pendulum.yaml"
SPRING_MASS = HERE / "study_models" / "spring_mass.yaml"
FOUR_BAR = HERE.parents[1] / "models" / "four_bar.yaml"
G = 9.81
