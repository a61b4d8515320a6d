"""Cases shared by the Hu et al. test files: the first inner hole of a mesh with its context."""
from meshlab_holefill.core.holes import boundary_loops, hole_context, vertex_face_incidence


def first_hole_context(V, F, rings=2):
    """The context of the mesh's first boundary loop that is not its longest (the longest: an outer border)."""
    loops = boundary_loops(F)
    inner = [lp for lp in loops if len(lp) < max(len(x) for x in loops)] or loops
    return hole_context(V, F, inner[0], vertex_face_incidence(F, len(V)), rings=rings)
