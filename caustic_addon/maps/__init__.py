"""Illumination maps: receivers' charts, the grids that hold caustic light, beams rasterised onto them, and the cache of them between renders."""
