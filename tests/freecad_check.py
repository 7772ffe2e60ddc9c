# Run by test_freecad through FreeCAD's command-line interpreter (freecadcmd):
# opens each <part>.step with Part.read and imports each <part>.csg with the
# OpenSCAD workbench's importCSG, and writes one line per part to
# results.txt in $CSGVOX_FREECAD_DIR:
#   part step_solids step_valid step_volume csg_roots csg_valid csg_volume csg_part_features
import os

import FreeCAD
import Part
import importCSG

folder = os.environ["CSGVOX_FREECAD_DIR"]
PRIMITIVES = {"Part::Box", "Part::Cylinder", "Part::Cone", "Part::Sphere", "Part::Revolution"}
with open(os.path.join(folder, "parts.txt")) as parts, \
        open(os.path.join(folder, "results.txt.partial"), "w") as out:
    for line in parts:
        name = line.split()[0]
        step = Part.Shape()
        step.read(os.path.join(folder, name + ".step"))
        doc = FreeCAD.newDocument("csg_" + name)
        importCSG.insert(os.path.join(folder, name + ".csg"), doc.Name)
        doc.recompute()
        # The solid is the one object nothing else uses that holds a solid
        # (the importer leaves the 2D circles of tori unused beside it).
        roots = [o for o in doc.Objects
                 if not o.InList and hasattr(o, "Shape") and o.Shape.Solids]
        csg = roots[0].Shape if len(roots) == 1 else None
        features = sum(1 for o in doc.Objects if o.TypeId in PRIMITIVES)
        out.write("%s %d %d %r %d %d %r %d\n" % (
            name, len(step.Solids), int(step.isValid()), step.Volume, len(roots),
            int(csg is not None and csg.isValid()), csg.Volume if csg else 0.0, features))
        FreeCAD.closeDocument(doc.Name)
os.rename(os.path.join(folder, "results.txt.partial"), os.path.join(folder, "results.txt"))
