"""Parameter studies: one model run at many parameter values, through Dask (docs/sweeps.md).

    design   the runs: grid axes, sampled parameters, seed (Study)
    block    a study from the YAML `study:` block or the command line, checked
    kept     the numbers kept per run (max(COLUMN), COLUMN@T, crossing(COLUMN), ...)
    runner   THE SEAM: one run at given parameter values (the only module that builds)
    execute  running the points in this process or on a Dask cluster
    sweep    prepare, collect, write (sweep.csv, sweep.parquet, metadata.json)
    full     --full: every run's results in one HDF5 file
    api      casmech.sweep(...) -> pandas DataFrame
"""
