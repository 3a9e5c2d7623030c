"""Reading a mechanism description: the TOML reader, its entries and parts, standard DH, limits, plausibility."""
