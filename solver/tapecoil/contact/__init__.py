"""Contact of a surface with itself: search, closest-point projection and penalty assembly.

:mod:`~tapecoil.contact.projection` is geometry alone (biquadratic quadrilaterals, closest
points, a buffered candidate search); :mod:`~tapecoil.contact.self_contact` puts a penalty on
the separation of a shell's mid-surface from itself and assembles it into a Newton solver.
"""
