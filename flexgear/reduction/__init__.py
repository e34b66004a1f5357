"""Model order reduction of FE gear bodies (layer 5): FE model -> reductor -> reduced body.

* :mod:`.interface` - which dofs the reduced coordinates prescribe (bore tied to the body frame,
  ring rim or bolts), :func:`~.interface.gear_interface`;
* :mod:`.reductor` - :class:`~.reductor.GuyanReductor` (static condensation) and
  :class:`~.reductor.CraigBamptonReductor` (plus fixed-interface modes up to a cutoff), one
  sparse factorisation shared by constraint modes, eigen-solve and residual flexibility;
* :mod:`.body` - :class:`~.body.ReducedBody`: reduced K, M, ``reconstruct(q)``;
* :mod:`.residual` - residual flexibility (quasi-static condensation of the modes left out);
* :mod:`.flank` - contact-point data for the solver: modal normal displacements at flank points
  of every tooth and residual compliance tables from the flanks of one tooth (per support
  period: cyclic symmetry) to both flanks of every tooth, every tooth distance; the near field
  removed from the self term (it stays in the Hertz contact law);
* :mod:`.gear` - one gear end to end, cached on disk; :mod:`.parallel` - several gears at once in
  worker processes.
"""
