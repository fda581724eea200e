"""Measured-data input and output: waveform readers and writers (CSV, NPZ, TDMS)."""

from msens.io.read import check_waveform_file, read_waveform, write_waveform
from msens.io.waveform import Channel, Waveform

__all__ = ["Channel", "Waveform", "check_waveform_file", "read_waveform", "write_waveform"]
