"""The comparison with Cycles: the same view rendered by Cycles, and the caustic render's error against it."""
