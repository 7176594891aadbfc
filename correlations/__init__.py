"""Published correlations, the apparent-viscosity calculator and the engineering estimate."""
