"""The passes: photons and beams from the lamps into the maps, and Whitted rays from the eye."""
