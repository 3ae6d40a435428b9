#include "config/obj_mesh.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace nephele {
namespace {

using ::testing::HasSubstr;

TEST(ObjMesh, ReadsVerticesAndFansPolygons) {
  TriangleMesh mesh;
  ASSERT_EQ(parseObjText("# a quad and a triangle\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                         "vn 0 0 1\nvt 0 0\ng body\nf 1/1/1 2/2/1 3//1 4\nf -1 -2 -3\n",
                         "m.obj", mesh),
            "");
  ASSERT_EQ(mesh.vertices.size(), 4u);
  EXPECT_EQ(mesh.vertices[2], glm::dvec3(1, 1, 0));
  ASSERT_EQ(mesh.triangles.size(), 3u);
  EXPECT_EQ(mesh.triangles[1], (std::array<std::uint32_t, 3>{0, 2, 3}));
  EXPECT_EQ(mesh.triangles[2], (std::array<std::uint32_t, 3>{3, 2, 1}));
}

TEST(ObjMesh, ErrorsNameTheLineAndLeaveTheMeshAlone) {
  TriangleMesh mesh;
  mesh.vertices = {{7, 7, 7}};
  EXPECT_THAT(parseObjText("v 0 0 0\nv 1 0\n", "m.obj", mesh),
              HasSubstr("m.obj:2: vertex needs three finite numbers"));
  EXPECT_THAT(parseObjText("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "m.obj", mesh),
              HasSubstr("m.obj:4: face index 4 is out of range (allowed: 1 to 3"));
  EXPECT_THAT(parseObjText("v 0 0 0\nv 1 0 0\nf 1 2\n", "m.obj", mesh),
              HasSubstr("at least three vertices"));
  EXPECT_THAT(parseObjText("v 0 0 nan\n", "m.obj", mesh), HasSubstr("finite"));
  EXPECT_THAT(parseObjText("v 0 0 0\n", "m.obj", mesh), HasSubstr("no faces"));
  EXPECT_THAT(loadObjMesh("/nonexistent/x.obj", mesh), HasSubstr("cannot read mesh file"));
  ASSERT_EQ(mesh.vertices.size(), 1u);
  EXPECT_EQ(mesh.vertices[0], glm::dvec3(7, 7, 7));
}

}  // namespace
}  // namespace nephele
