"""Sampled signals: processing, pulse features, checks of measured records."""
