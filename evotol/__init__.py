"""evotol: cost-optimal tolerance allocation for robots and mechanisms."""
__version__ = "0.1.0"
