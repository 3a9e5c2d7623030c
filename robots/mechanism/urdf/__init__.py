"""Serial arms from URDF, read with Pinocchio, and their agreement with Pinocchio."""
