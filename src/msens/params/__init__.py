"""Published parameter sets and material records, each cited, and physical constants."""
