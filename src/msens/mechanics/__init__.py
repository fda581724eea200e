"""Contact mechanics of the beads, below both the chain and the field model."""
