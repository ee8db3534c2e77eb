"""The names the user chooses from (checked before anything heavy is imported); the modules that
implement them check that they implement exactly these."""

MODELS = ("plane_strain", "plane_stress", "axisymmetric")
UPDATES = ("sr", "hughes_winget", "polar", "svk", "neo_hooke")
PLASTIC_UPDATES = ("sr", "hughes_winget")      # those that carry a rotated old stress
CONTACT_METHODS = ("penalty", "nitsche")
PREDICTORS = {"none": False, "linear": 1, "quadratic": 2, "tangent": "tangent"}
LAWS = ("j2", "chen")
