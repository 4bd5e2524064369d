"""The commands of ``tapecoil``, one function ``cmd_<name>(args) -> exit status`` each.

They import DOLFINx, MPI and the solvers inside the function, not at the top of the module, so
that the commands that compute no finite elements (``theory``, ``config``) start without them.
"""
