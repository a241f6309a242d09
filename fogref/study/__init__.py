"""Studies of the game fog models against the truth (Unreal first).

Modules (one concept each):

* :mod:`~fogref.study.fit`     ``fogref fit``'s scene reading and the cosine-lobe vs HG
  table's pages (the fits themselves are :mod:`fogref.mapping`)
* :mod:`~fogref.study.budget`  the error budget: a telescoping chain from the
  path-traced truth to Unreal, one effect per step
* :mod:`~fogref.study.unreal`  the Unreal study: fit + comparison + budget + README
* :mod:`~fogref.study.sweep`   declarative error studies over many configurations, on Dask
* :mod:`~fogref.study.droplet_phase` what HG and the engines' lobe cost in droplet fog

The command lines (``fogref fit``, ``fogref study``, ``fogref sweep``) are
:mod:`fogref.cli.fit`, :mod:`fogref.cli.study` and :mod:`fogref.cli.sweep`.
"""
