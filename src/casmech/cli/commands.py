"""The subcommands of `casmech`, one module each.

COMMANDS maps a command's name to (its module in this package, its one-line help); every module
defines add_arguments(parser) and run(args) -> int (the exit code). cli.py builds the parser from
this table and imports only the module of the command being run: a new command is a new module
and one new entry here. Modules import what only some of their paths use (plotting, HDF5,
code generation) inside the functions that use it.
"""

COMMANDS = {
    "check": ("check", "validate a model; print DOF, rank, redundancy"),
    "run": ("run", "run the model's analysis; write results.csv (or results.h5)"),
    "sweep": ("sweep", "run the model at every point of a parameter study (grid or samples; "
                       "Dask); write sweep.csv"),
    "sensitivity": ("sensitivity",
                    "derivatives of results columns w.r.t. parameters (IDAS sensitivities)"),
    "optimize": ("optimize",
                 "optimal control (ocp: block) or parameter estimation (estimate: block)"),
    "compile": ("compile",
                "generate C for the model's functions and build the shared library into DIR"),
    "export": ("export", "write an FMI 2.0 FMU (Model Exchange and Co-Simulation) of the model"),
    "cache": ("cache", "show or clear the compiled-model cache"),
    "plot": ("plot", "plot results columns or presets against time (matplotlib)"),
    "inspect": ("inspect", "print coordinates, constraint rows by joint with YAML lines, DOF, "
                           "rank"),
    "import": ("import_cmd",
               "convert an Adams .adm deck, a simEngine3D .mdl/.acf model, a URDF robot or a "
               "MuJoCo MJCF model (.xml) to casmech YAML"),
    "animate": ("animate", "write a VTK time series (ParaView) and a self-contained HTML player"),
}
