"""FMI 2.0 export (docs/fmu.md): `casmech export MODEL.yaml -o NAME.fmu`.

    model.py        what the FMU exposes: parameters by kind, inputs; the traced lowering
    start.py        the start state casmech computes at the model's own values
    system.py       the CasADi functions the C calls (ODE, outputs, start, projection)
    outputs.py      the results row as one expression of the state
    description.py  modelDescription.xml
    archive.py      the C, its build and the archive (export)
    c/              the FMI functions and the Co-Simulation integrator in C
"""
