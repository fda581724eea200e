"""What a sensor reads: the chain's observation operators, the pick-up coil, its circuit."""
