"""The scenes the measurements and the engine tests build, each with what
is known of it exactly (a closed form, or the pixel reference it is
measured against)."""
