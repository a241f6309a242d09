"""``fogref sweep SWEEP.toml``: a declarative error study over many configurations, on Dask.

A sweep is a TOML file: the scenes, the parameters to vary (any ``$default`` of
the scene, or a model parameter), the design (grid, zipped lists, seeded random or
Latin hypercube), the models to compare, the sample count and seed policy, and the
outputs.  Each *configuration* (one scene + one set of parameter values) is one
Dask task: it renders the ground truth, or reuses it from a content-addressed
cache, then runs every model against it (``compare`` with figures off) and returns
one row per model.  The rows are gathered into one tidy table (CSV + Parquet) with
plots of each metric against each swept parameter beside it.

Example ``SWEEP.toml``::

    [sweep]
    name = "unreal_sun_falloff_g"
    scenes = ["scenes/valley.xml"]     # relative to the TOML file, else to the working directory
    out = "."                          # output folder (relative to the TOML file; default: its folder)
    cache = "out/sweep_cache"          # ground-truth cache (relative to the working directory)

    [render]
    spp = 16
    seed = 0
    seed_policy = "fixed"              # or "per_config": seed derived from the config's values
    overrides = { res = 64, resy = 36 } # fixed $defaults for every configuration

    [design]
    kind = "grid"                      # "grid" | "list" | "random" | "lhs"
    # n = 48; seed = 0                 # random / lhs only
    # max_configs = 100000             # the design is sized before it is built and refused above this

    [parameters.sun_elevation]         # a scene $default (each value checked by the scene and its medium) ...
    values = [2, 8, 20, 45]            # distinct values; one label per target, not also in overrides
    [parameters.FogHeightFalloff]      # ... under a label: falloff = 0.0693147 * value
    target = "falloff"
    scale = 0.0693147
    values = [0.1, 0.2, 0.4, 0.8]
    [parameters."ue4.start_distance"]  # a model parameter: "<model label>.<parameter>"
    range = [0, 100]                   # random / lhs: uniform in range (log = true: log-uniform)

    [[models]]
    name = "ue4"                       # a model name (built-in, "my_pkg.fog:MyFog" or an entry
                                       # point of group fogref.models); label defaults to the name
                                       # (its Class part for "module:Class")
    from_scene = true                  # parameters from the truth's physical fog, like --from-scene
    params = {}                        # then these override them

    [execution]
    retries = 1                        # Dask retries of a failing configuration

    [outputs]
    table = "results"                  # results.csv, results.parquet (inside the output folder)
    plots = true                       # plots/<metric>_vs_<parameter>.png
    plot_metrics = ["final.all.rmse", "final.all.relmse"]   # default: every final.all.* metric
    budget = false                     # true: Unreal's error budget for every "ue4" model (one extra
                                       # render per configuration: the scene without its sun)
    perceptual = true                  # false: no ΔE2000 or FLIP columns, every other column the
                                       # same (the example sweep 1.37x faster; FLIP is a quarter of
                                       # a configuration's work)

Output folder::

    results.csv, results.parquet   one row per configuration x model
    configs/<config id>.json       one result per configuration (written atomically; resume reads them)
    plots/*.png                    each plotted metric against each swept parameter
    sweep.json                     the resolved design and the command
    sweep-workers.log              the LocalCluster workers' own output (tracebacks at Ctrl-C)

No output may replace an input (the sweep file, the scenes, the files they load):
:func:`run_sweep` compares resolved paths before any work.

``[sweep] kind = "ue_pathtracer"``: each configuration compares Unreal's path-traced fog with the exact
fog in closed form, nothing rendered (:func:`fogref.study.ue_pathtracer.closed_form_row`); ``[fixed]``,
``[sun]``, ``[views]`` replace ``[render]``, ``[[models]]`` (``reports/sweeps/ue_pathtracer/SWEEP.toml``).

Modules: :mod:`~fogref.study.sweep.spec` (the TOML schema, :func:`load_sweep`),
:mod:`~fogref.study.sweep.design` (the designs, :func:`build_configs`),
:mod:`~fogref.study.sweep.task` (one configuration on a worker, :func:`run_config`),
:mod:`~fogref.study.sweep.run` (Dask, resume, :func:`run_sweep`) and
:mod:`~fogref.study.sweep.table` (the table and plots).
"""

from __future__ import annotations

from fogref.study.sweep.design import build_configs, design_points
from fogref.study.sweep.run import run_sweep
from fogref.study.sweep.spec import SweepSpec, load_sweep
from fogref.study.sweep.table import plot_table, write_table
from fogref.study.sweep.task import run_config

__all__ = [
    "SweepSpec",
    "build_configs",
    "design_points",
    "load_sweep",
    "plot_table",
    "run_config",
    "run_sweep",
    "write_table",
]
