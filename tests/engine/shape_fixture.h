#pragma once
// Loads an in-memory OCCT shape through the engine's own reader (via a temporary .brep file), so
// tests build B-reps with BRepBuilderAPI / BRepPrimAPI and mesh them like a user's file; and
// loads the bundled models.

#include <gtest/gtest.h>
#include <unistd.h>

#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Shape.hxx>
#include <filesystem>
#include <gp_Trsf.hxx>
#include <gp_Vec.hxx>
#include <memory>
#include <string>

#include "rdmesh/engine.h"

namespace rdmesh {

inline std::shared_ptr<const Model> LoadShape(const TopoDS_Shape& shape, const std::string& name) {
  std::string path = (std::filesystem::temp_directory_path() /
                      ("rdmesh_test_" + std::to_string(::getpid()) + "_" + name + ".brep"))
                         .string();
  BRepTools::Write(shape, path.c_str());
  auto model = LoadModel(path);
  std::filesystem::remove(path);
  EXPECT_TRUE(model.ok()) << model.status().ToString();
  return model.ok() ? *model : nullptr;
}

/// `shape` and a copy of it moved by (dx, 0, 0), in one compound: the copy's faces are placed
/// copies (one TShape under two locations).
inline TopoDS_Compound PlacedTwice(const TopoDS_Shape& shape, double dx) {
  gp_Trsf shift;
  shift.SetTranslation(gp_Vec(dx, 0, 0));
  TopoDS_Compound both;
  BRep_Builder builder;
  builder.MakeCompound(both);
  builder.Add(both, shape);
  builder.Add(both, shape.Moved(TopLoc_Location(shift)));
  return both;
}

/// MeshModel's result, failing the test (and returning an empty result) when it is an error.
inline MeshResult MeshOrDie(const Model& model, const MeshOptions& options = MeshOptions()) {
  auto result = MeshModel(model, options);
  EXPECT_TRUE(result.ok()) << result.status().ToString();
  return result.ok() ? std::move(*result) : MeshResult();
}

/// Loads a bundled model (tests/data) by file name.
inline std::shared_ptr<const Model> LoadData(const std::string& file) {
  auto model = LoadModel(std::string(RDMESH_TEST_DATA) + "/" + file);
  EXPECT_TRUE(model.ok()) << model.status().ToString();
  return model.ok() ? *model : nullptr;
}

}  // namespace rdmesh
