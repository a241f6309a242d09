"""Self-contained HTML reports: one file per report that works from ``file://`` with no network.

* :mod:`~fogref.html.inline`: the encodings a page embeds (half-float images, masks, PNGs as
  base64) and small HTML pieces, among them the notebook displays of ``Truth`` and
  ``CheckResult`` (registered by ``%load_ext fogref.html.notebook``);
* :mod:`~fogref.html.assets`: the viewer's CSS and JavaScript (its tone map is
  :func:`fogref.display.tone_map`, the same formula; ``tests/test_html_browser.py`` checks
  a probe pixel against Python);
* :mod:`~fogref.html.page`: the page skeleton, tables and figures;
* :mod:`~fogref.html.viewer`: the viewer's data from a compare report folder and a truth;
* :mod:`~fogref.html.reports`: ``report.html`` of ``fogref compare``, ``study``, ``sweep`` and
  a batch of images.

Importing this package does no work.
"""
