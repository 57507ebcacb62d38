"""The OpenCASCADE layer: the only package (besides the mesher) that imports OCP.

Reading STEP, IGES and BREP files (:mod:`.reader`), walking the B-rep in ``TopExp::MapShapes`` order
(:mod:`.topology`, :mod:`.shapedump`), edges as black-box curves (:mod:`.edgecurve`, :mod:`.edgetable`) and
``refine_shape`` (:mod:`.shape`). Nothing is imported here, so ``import cadedge`` costs no OCCT.
"""
