"""Embree: the scene's triangles in one BVH, closest hits and shadow rays, and the mesh topology it needs."""
