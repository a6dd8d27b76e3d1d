"""The smallest study the tests run end to end: two CFAs on a 60 x 40
Macbeth chart, one demosaic, two noise realisations (a few seconds)."""

TINY = """\
name = "tiny"
seed = 1
seeds = 2
scenes = ["macbeth"]
cfas = ["bayer", "rgbw1"]
demosaics = ["bilinear"]
luminances = [100]
[render.macbeth]
width = 60
height = 40
"""

#: appended to a config: no report (the tables only)
NO_REPORT = """\
[output]
report = false
"""
