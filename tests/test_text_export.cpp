#include <gtest/gtest.h>

#include <sstream>

#include "io/text_export.h"
#include "io/tree_names.h"

namespace csgvox {
namespace {

TEST(TextExport, ExpressionUsesLeafNames) {
  const CsgTree t = CsgTree::subtract(
      {CsgTree::unite({CsgTree::leaf(Box{}, "base"), CsgTree::leaf(Cylinder{}, "boss")}),
       CsgTree::leaf(Cylinder{Vec3(1, 0, 0), Vec3::UnitZ(), 0.5, 2.0}, "hole")});
  EXPECT_EQ(treeExpression(t), "difference(union(base, boss), hole)");
}

TEST(TextExport, UnnamedLeavesGetTypeNamesAndBadNamesAreReplaced) {
  const CsgTree t = CsgTree::intersect({CsgTree::leaf(Sphere{}), CsgTree::leaf(Sphere{}),
                                        CsgTree::leaf(Torus{}, "not an identifier")});
  EXPECT_EQ(treeExpression(t), "intersection(sphere1, sphere2, torus1)");
}

TEST(TextExport, DefinitionsFollowTheExpressionOnePerLine) {
  const CsgTree t =
      CsgTree::complement(CsgTree::leaf(Cone{Vec3(0, 0, 1), Vec3::UnitZ(), 2.0, 0.0, 3.0}, "tip"));
  std::ostringstream s;
  writeTreeText(s, t);
  EXPECT_EQ(s.str(),
            "complement(tip)\n"
            "tip = cone(center=[0, 0, 1], axis=[0, 0, 1], radius_bottom=2, radius_top=0, "
            "height=3)\n");
}

TEST(TreeNames, NumbersRoundTripExactly) {
  for (double v : {0.1, 1.0 / 3.0, -2.5e-300, 123456789.125, 1e22}) {
    EXPECT_EQ(std::stod(formatNumber(v)), v);
  }
  EXPECT_EQ(formatNumber(-0.0), "0");
  EXPECT_EQ(formatNumber(2.5), "2.5");
}

}  // namespace
}  // namespace csgvox
