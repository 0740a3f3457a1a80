"""Light leaving the lamps: Blender's units as radiometry, and where lamp rays go, aimed at the casters."""
