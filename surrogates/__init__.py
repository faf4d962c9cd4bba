"""Response surfaces for black-box optimization: designs of experiments, a quadratic surface
fitted by least squares (optionally gradient-enhanced), and search-region rules (ARSM, SRSM).

Everything works in unit coordinates of the design box; `to_unit` / `to_bounds` map to and from
physical bounds. Importing does no numerical work.
"""

from .doe import (
    as_bounds,
    central_composite,
    latin_hypercube,
    maximin_fill,
    sobol,
    star,
    to_bounds,
    to_unit,
)
from .quadratic import QuadraticSurface, fit_quadratic, n_terms
from .region import Region, arsm_update, inherit, safeguard, second_best, srsm_update

__all__ = [
    "as_bounds",
    "central_composite",
    "latin_hypercube",
    "maximin_fill",
    "sobol",
    "star",
    "to_bounds",
    "to_unit",
    "QuadraticSurface",
    "fit_quadratic",
    "n_terms",
    "Region",
    "arsm_update",
    "inherit",
    "safeguard",
    "second_best",
    "srsm_update",
]
