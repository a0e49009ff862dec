"""The community hub: one folder, kept in git, where many labs' friction-map packages meet.

A hub is a plain folder (:mod:`tribopipe.hub.folder`)::

    hub.toml                         the hub's title (``hub init``)
    README.md                        how a lab contributes
    CITATION.cff, .zenodo.json       how to cite the hub; the metadata of a release's DOI
    .github/workflows/hub-check.yml  every pull request checked with ``tribopipe hub check``
    labs/<lab>/<release>/            one published package per lab and release

``hub check`` (:mod:`tribopipe.hub.check`) checks a package as ``map validate
--recompute`` does, then against the hub: materials, the same raw content under another
lab, conflicts with the hub's rows. ``hub add`` files a package that passes. ``hub build``
(:mod:`tribopipe.hub.site`) writes the merged map and a static site.
"""
