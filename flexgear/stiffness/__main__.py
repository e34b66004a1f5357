"""``python -m flexgear.stiffness``: FE/ISO stiffness ratios of the MERCURY 1-A pairs."""
import sys

from .iso_comparison import main

if __name__ == "__main__":
    sys.exit(main())
