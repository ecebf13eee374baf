"""How accurate the identification's C_i and C_f are on records of known truth, whatever the
noise: the floor under an interval that pooling many runs or decays would otherwise narrow
without end.

A single record's 95 % intervals are the noise's (their coverage is what the validation matrix,
``make validate``, checks). Pooling runs or a long record's segments (:mod:`fsi_lab.
aggregate_fit`) shrinks that part as one over the square root of the decays, while the
method's own systematic errors stay: the filter correction of the first extrema, the base still
forcing a mode where its decay is taken to start. On the matrix's clean records and the
simulated wet bench (noise 0.1 % or less of the peak, or the bench's) those errors reach 0.29 %
on C_i and 2.0 % on C_f (the bench excited by its default ramp derivative, 0.01 V s); six runs
of the bench pinned C_f to +-0.6 % at -0.9 % from the truth, and a 20 min record's 120 decays
to +-0.06 % at -0.8 %. A union's interval therefore holds these half-widths (relative to the
value) added in quadrature to its own, and is never narrower than them.

Being relative, the floor vanishes with the value: a C_f near 0 (little quadratic damping)
keeps its noise interval, which then holds 0 anyway. A single record's intervals are left as
the noise makes them: their coverage over the noise is what the matrix checks (90 to 98 %),
but on a record far cleaner than the matrix's they can be narrower than these errors (the
simulated bench's default run: C_f 32.69, 95 % 32.4 to 32.98, against 33); read them with
this accuracy in mind.
"""

from __future__ import annotations

#: Relative 95 % half-width below which no pooled interval of C_i (the law's ``a``) or C_f
#: (``beta``) goes.
ACCURACY = {"c_i": 0.003, "c_f": 0.02}
#: The same, by the quadratic law's parameter names.
LAW_ACCURACY = {"a": ACCURACY["c_i"], "beta": ACCURACY["c_f"]}


def describe() -> str:
    """``+-0.3 % on C_i, +-2 % on C_f``: the accuracy in words."""
    return f"+-{100 * ACCURACY['c_i']:g} % on C_i, +-{100 * ACCURACY['c_f']:g} % on C_f"
