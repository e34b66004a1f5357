"""Gear geometry (ISO 21771 involute spur gears with generated roots), materials, tooth faults and
manufacturing errors (faults, modified outlines) and the engagement kinematics: layer 1."""
