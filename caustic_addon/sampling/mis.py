"""Weights that combine two sampling strategies of one integral (Veach
1997, multiple importance sampling)."""

from __future__ import annotations

from ..util.jit import inline


@inline
def power_heuristic1(count_f, pdf_f, count_g, pdf_g):
    """The weight of a sample that strategy f, taken `count_f` times, drew
    with density `pdf_f`, where strategy g, taken `count_g` times, would
    draw it with `pdf_g`: (n_f p_f)^2 / ((n_f p_f)^2 + (n_g p_g)^2), the
    power heuristic of exponent 2 (Veach 1997, section 9.2.4, as Cycles
    weighs light and BSDF samples). With g's weight of the same sample the
    two sum to 1; 0 where neither draws it."""
    f, g = count_f * pdf_f, count_g * pdf_g
    return f * f / (f * f + g * g) if f > 0.0 else 0.0
