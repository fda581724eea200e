"""Study files: schema, parsing, plausibility limits, and the mapping of a study to models."""
