"""Geometric building blocks shared by two or more algorithms (or by an algorithm and the core).

Plain numpy arrays in and out; nothing here imports the core, the algorithms or pymeshlab.

* :mod:`.quality`: areas, normals, angles, edge lengths, the 2r/R triangle quality.
* :mod:`.topology`: half-edge twins, interior edges and 1-rings of small face lists.
* :mod:`.laplacian`: uniform and cotangent Laplacians, tangential umbrella smoothing.
* :mod:`.flips`: edge relaxation by swaps (circumsphere, unfolded-angle or scored tests).
* :mod:`.refine`: Pfeifle-Seidel density refinement (Hu et al. Sec. III.C; Xu et al.'s fallback).
* :mod:`.pca`: least-squares planes and plane frames.
* :mod:`.triangulate`: constrained Delaunay triangulation of a simple polygon (Triangle).
* :mod:`.dihedral_triangulation`: a 3D loop triangulated by least bend against its neighbours (Liepa's weight).
* :mod:`.caps`: caps of loop-only triangles split open by an inner vertex.
* :mod:`.segments`: exact segment distances, simple-polygon tests.
* :mod:`.intersections`: topology-aware triangle-triangle intersection queries.
* :mod:`.development`: a border loop laid out in the plane with its edge lengths and surface angles.
* :mod:`.sets`: np.unique, np.isin and np.setdiff1d of integer arrays, by sorting.
* :mod:`.sparse_lu`: SuperLU in its symmetric mode, for symmetric systems with a dominant diagonal.
"""

__all__ = ["quality", "topology", "laplacian", "flips", "refine", "pca",
           "triangulate", "dihedral_triangulation", "caps", "segments", "intersections", "development", "sets",
           "sparse_lu"]
