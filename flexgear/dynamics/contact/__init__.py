"""Tooth contact: the contact laws, the search of the contacts on the gears' outlines and the
joint solve of the compliant contacts."""
