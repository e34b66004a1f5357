"""sphinx-gallery image scraper for the PNG files an example writes.

flexgear draws its figures without pyplot (``flexgear.style.figure``), so the examples save
them (``fig.savefig("ex01_spur_spectrum.png")``) when run as scripts; sphinx-gallery runs them
as scripts in their own folder. This scraper moves each new PNG there into the gallery's
images, so the build leaves nothing in ``examples/``.
"""
import shutil
from pathlib import Path

from sphinx_gallery.scrapers import figure_rst


def png_scraper(block, block_vars, gallery_conf):
    """Move the PNG files the example's code block wrote into the gallery; their reST."""
    folder = Path(block_vars["src_file"]).parent
    names = []
    for png in sorted(folder.glob("*.png")):
        target = block_vars["image_path_iterator"].next()
        shutil.move(str(png), target)
        names.append(target)
    return figure_rst(names, gallery_conf["src_dir"])
