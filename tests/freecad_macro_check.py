# Run by test_freecad_macro through FreeCAD's command-line interpreter
# (freecadcmd): runs each <part>.FCMacro listed in parts.txt in
# $CSGVOX_FREECAD_DIR, reads <part>.step, and writes one line per part to
# results.txt:
#   part solids valid volume step_volume
# A part listed with "edit NAME VALUE P1x P1y P1z P2x P2y P2z" also has cell
# NAME of the Parameters sheet set to VALUE and recomputed; its line then
# ends with the volume after the edit and whether P1 and P2 lie inside the
# solid before and after it (0/1 each: p1_before p2_before p1_after p2_after).
import os

import FreeCAD
import Part

folder = os.environ["CSGVOX_FREECAD_DIR"]
with open(os.path.join(folder, "parts.txt")) as parts, \
        open(os.path.join(folder, "results.txt.partial"), "w") as out:
    for line in parts:
        words = line.split()
        name = words[0]
        scope = {}
        exec(open(os.path.join(folder, name + ".FCMacro")).read(), scope)
        doc = scope["doc"]
        shape = doc.getObject("part").Shape
        step = Part.Shape()
        step.read(os.path.join(folder, name + ".step"))
        text = "%s %d %d %r %r" % (name, len(shape.Solids), int(shape.isValid()), shape.Volume,
                                   step.Volume)
        if len(words) > 1 and words[1] == "edit":
            cell, value = words[2], words[3]
            p1 = FreeCAD.Vector(*map(float, words[4:7]))
            p2 = FreeCAD.Vector(*map(float, words[7:10]))
            before = (shape.isInside(p1, 1e-6, True), shape.isInside(p2, 1e-6, True))
            sheet = doc.getObject("Parameters")
            sheet.set(sheet.getCellFromAlias(cell), value)
            doc.recompute()
            edited = doc.getObject("part").Shape
            after = (edited.isInside(p1, 1e-6, True), edited.isInside(p2, 1e-6, True))
            text += " %r %d %d %d %d" % ((edited.Volume,) + tuple(int(b) for b in before + after))
        out.write(text + "\n")
        FreeCAD.closeDocument(doc.Name)
os.rename(os.path.join(folder, "results.txt.partial"), os.path.join(folder, "results.txt"))
