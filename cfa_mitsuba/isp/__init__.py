"""isp/: white balance, demosaicing, colour correction -> XYZ and sRGB."""
