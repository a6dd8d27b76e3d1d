"""optics/: scene radiance to sensor-plane irradiance (f-number, lens
transmittance, relative illumination, diffraction OTF)."""
