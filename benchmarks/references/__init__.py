"""Exact or unbiased references the measurements compare against: the
float64 ball lens (reference.py), meshed water's own particle tracer
(water_reference.py), Mitsuba 3's particle tracer (mitsuba_ptracer.py, in
Mitsuba's venv), and the accuracy metric (metrics.py)."""
