"""The SI units an error source or a workspace coordinate may declare (values inside are SI)."""

UNITS = ("m", "rad")
