"""Gear geometry (ISO 21771 involute spur gears with generated roots) and materials: layer 1."""
