"""Deterministic random numbers, low-discrepancy sequences and warps onto discs, cones and frames."""
