"""Tooth and mesh stiffness of spur gears from plane finite elements plus Hertzian contact.

Layer 4 (``gears -> fe -> stiffness``). Modules: :mod:`.hertz` (closed forms),
:mod:`.compliance` (one tooth, FE), :mod:`.loaded_mesh` (a pair), :mod:`.iso_comparison` and
:mod:`.iso6336` (ISO 6336-1), :mod:`.compliance3d` (3D vs plane models), :mod:`.fe_convergence`,
:mod:`.impact_fit` (an IMPACT law fitted to the loaded-mesh transmission error, for rigid
models), :mod:`.crack` (a tooth with a root crack), :mod:`.crack_energy` (the published
potential-energy crack model) and :mod:`.crack3d` (a crack over part of the face width).
``python -m flexgear.stiffness`` prints the ISO comparison for the MERCURY 1-A pairs.

Method (patch load, near field removed in closed form, nonlinear Hertz, load sharing, contact
outside the path): see the theory page *Lumped model*, section *FE mesh stiffness*; the
crack: the theory page *Root crack*. All SI: m, N, N/m; compliances m/N; stiffness per face
width N/m^2.
"""
