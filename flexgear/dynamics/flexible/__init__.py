"""Flexible gears: Craig-Bampton bodies in the model, their flank compliance at the contacts,
modal coordinates and condensed modes, and the full-order reference."""
