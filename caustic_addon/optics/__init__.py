"""The physics of light at and inside glass: reflection, refraction, Fresnel, absorption, dispersion and the spectrum."""
