"""Time integration (HHT-alpha with Newton iterations): the force evaluation, the compiled time
loop and its buffers, and the Python driver."""
