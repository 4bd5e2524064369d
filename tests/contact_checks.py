"""Checks shared by the contact tests (imported by them; not a test module)."""


def central_force_difference(term, move, template):
    """(F(x0 + d) - F(x0 - d)) / 2 of ``term``'s residual F, where ``move(sign)`` puts the
    state at x0 + sign d (sign 1, -1, then 0 to restore it); a vector like ``template``."""

    def force(sign):
        move(sign)
        b = template.duplicate()
        b.set(0.0)
        term.add_residual(b)
        return b

    fp, fm = force(1.0), force(-1.0)
    move(0.0)
    fp.axpy(-1.0, fm)
    fp.scale(0.5)
    fm.destroy()
    return fp
