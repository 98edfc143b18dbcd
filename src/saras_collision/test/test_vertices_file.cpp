// Vertices-file parser: format, scaling, and line-numbered errors for every malformed case.
#include "saras_collision/vertices_file.h"

#include <gtest/gtest.h>

#include <sstream>

namespace
{
const char* kUnitBox =
    "0 0 0\n1 0 0\n1 0 1\n0 0 1\n0 1 0\n1 1 0\n1 1 1\n0 1 1\n";

bool parse(const std::string& text, std::vector<saras_collision::OrientedBox>& boxes, std::string& error,
           double scaling = 1.0)
{
  std::istringstream in(text);
  return saras_collision::parseVertices(in, scaling, 1e-6, boxes, error);
}
}  // namespace

TEST(VerticesFile, ParsesCommentsAndScaling)
{
  std::vector<saras_collision::OrientedBox> boxes;
  std::string error;
  ASSERT_TRUE(parse(std::string("# header\n2  # two boxes\n\n") + kUnitBox + "# second\n" + kUnitBox, boxes, error,
                    0.001))
      << error;
  ASSERT_EQ(boxes.size(), 2u);
  EXPECT_TRUE(boxes[0].center.isApprox(Eigen::Vector3d(0.0005, 0.0005, 0.0005)));
  EXPECT_TRUE(boxes[1].half.isApprox(Eigen::Vector3d(0.0005, 0.0005, 0.0005)));
  ASSERT_TRUE(parse("0\n", boxes, error)) << error;
  EXPECT_TRUE(boxes.empty());
}

TEST(VerticesFile, ErrorsNameTheLine)
{
  std::vector<saras_collision::OrientedBox> boxes;
  std::string error;
  EXPECT_FALSE(parse("", boxes, error));
  EXPECT_NE(error.find("empty file"), std::string::npos) << error;

  EXPECT_FALSE(parse("# c\ntwo\n", boxes, error));
  EXPECT_EQ(error.find("line 2:"), 0u) << error;

  EXPECT_FALSE(parse("-1\n", boxes, error));
  EXPECT_EQ(error.find("line 1:"), 0u) << error;

  EXPECT_FALSE(parse(std::string("1\n") + "0 0 0\n1 0 0\n1 0\n", boxes, error));
  EXPECT_EQ(error.find("line 4:"), 0u) << error;
  EXPECT_NE(error.find("expected 3 coordinates"), std::string::npos) << error;

  EXPECT_FALSE(parse(std::string("1\n") + "0 0 0\n1 0 0\n1 0 1\n0 zero 1\n", boxes, error));
  EXPECT_EQ(error.find("line 5:"), 0u) << error;
  EXPECT_NE(error.find("'zero'"), std::string::npos) << error;

  EXPECT_FALSE(parse(std::string("1\n") + "0 0 0\n1 0 nan\n", boxes, error));
  EXPECT_EQ(error.find("line 3:"), 0u) << error;

  EXPECT_FALSE(parse(std::string("2\n") + kUnitBox + "0 0 0\n", boxes, error));
  EXPECT_EQ(error.find("line 10:"), 0u) << error;
  EXPECT_NE(error.find("unexpected end of file in box 1"), std::string::npos) << error;

  // Vertices 2 and 3 swapped: not the documented order.
  EXPECT_FALSE(parse("1\n0 0 0\n1 0 0\n0 0 1\n1 0 1\n0 1 0\n1 1 0\n1 1 1\n0 1 1\n", boxes, error));
  EXPECT_EQ(error.find("lines 2-9: box 0"), 0u) << error;

  EXPECT_FALSE(parse(std::string("1\n") + kUnitBox + "1 2 3\n", boxes, error));
  EXPECT_EQ(error.find("line 10:"), 0u) << error;
  EXPECT_NE(error.find("unexpected data"), std::string::npos) << error;

  EXPECT_FALSE(parse("1\n", boxes, error, 0.0));
  EXPECT_NE(error.find("scaling"), std::string::npos) << error;

  EXPECT_FALSE(saras_collision::loadVerticesFile("/nonexistent/v.txt", 1.0, 1e-6, boxes, error));
  EXPECT_EQ(error.find("/nonexistent/v.txt: cannot open"), 0u) << error;
}
