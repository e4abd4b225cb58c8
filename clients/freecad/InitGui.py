# The rdmesh workbench: one command, "Mesh on rdmeshd" (Rdmesh_Mesh), in its own toolbar and
# menu. FreeCAD runs this file at start-up when this folder is linked into its Mod folder
# (clients/freecad/README.md); the folder is then on sys.path, so rdmesh_freecad imports.
import FreeCADGui


class RdmeshMeshCommand:
    """Meshes the selection (or every visible shape) on rdmeshd: rdmesh_freecad.main()."""

    def GetResources(self):
        return {"MenuText": "Mesh on rdmeshd",
                "ToolTip": "Mesh the selected shapes (or every visible shape) on an rdmeshd "
                           "server: a watertight mesh with one segment per B-rep face"}

    def IsActive(self):
        import FreeCAD
        return FreeCAD.ActiveDocument is not None

    def Activated(self):
        import rdmesh_freecad
        rdmesh_freecad.main()


class RdmeshWorkbench(FreeCADGui.Workbench):
    MenuText = "rdmesh"
    ToolTip = "Watertight meshes from an rdmeshd server"

    def Initialize(self):
        self.appendToolbar("rdmesh", ["Rdmesh_Mesh"])
        self.appendMenu("rdmesh", ["Rdmesh_Mesh"])

    def GetClassName(self):
        return "Gui::PythonWorkbench"


FreeCADGui.addCommand("Rdmesh_Mesh", RdmeshMeshCommand())
FreeCADGui.addWorkbench(RdmeshWorkbench())
