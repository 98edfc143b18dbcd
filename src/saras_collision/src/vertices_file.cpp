#include "saras_collision/vertices_file.h"

#include <cmath>
#include <fstream>
#include <sstream>

namespace saras_collision
{
namespace
{
/// Tokenizer over lines that remembers the line number of every token.
class LineReader
{
public:
  explicit LineReader(std::istream& in) : in_(in)
  {
  }

  /// Next non-empty, non-comment line split into tokens; false at end of input.
  bool nextLine(std::vector<std::string>& tokens)
  {
    std::string line;
    while (std::getline(in_, line))
    {
      ++line_number_;
      const std::size_t hash = line.find('#');
      if (hash != std::string::npos)
        line.erase(hash);
      std::istringstream ss(line);
      tokens.clear();
      std::string tok;
      while (ss >> tok)
        tokens.push_back(tok);
      if (!tokens.empty())
        return true;
    }
    return false;
  }

  int line() const
  {
    return line_number_;
  }

private:
  std::istream& in_;
  int line_number_ = 0;
};

bool parseDouble(const std::string& s, double& value)
{
  std::size_t used = 0;
  try
  {
    value = std::stod(s, &used);
  }
  catch (const std::exception&)
  {
    return false;
  }
  return used == s.size() && std::isfinite(value);
}

/// The first line: the number of boxes NUM (integer in [0, 1000000]). @return false with @p error
bool readBoxCount(LineReader& reader, std::vector<std::string>& tokens, long& num, std::string& error)
{
  if (!reader.nextLine(tokens))
  {
    error = "line " + std::to_string(reader.line()) + ": empty file, expected the number of boxes NUM";
    return false;
  }
  std::size_t used = 0;
  try
  {
    num = std::stol(tokens[0], &used);
  }
  catch (const std::exception&)
  {
    used = 0;
  }
  if (tokens.size() != 1 || used != tokens[0].size() || num < 0 || num > 1000000)
  {
    error = "line " + std::to_string(reader.line()) + ": expected the number of boxes NUM (integer >= 0), got '" +
            tokens[0] + (tokens.size() > 1 ? " ..." : "") + "'";
    return false;
  }
  return true;
}

/// The 8 vertex lines of box @p b (of @p num), scaled to metres into @p v; @p first_line is the
/// line number of its first vertex. @return false with @p error
bool readBoxVertices(LineReader& reader, std::vector<std::string>& tokens, long b, long num, double scaling,
                     Eigen::Vector3d v[], int& first_line, std::string& error)
{
  for (int c = 0; c < 8; ++c)
  {
    if (!reader.nextLine(tokens))
    {
      error = "line " + std::to_string(reader.line()) + ": unexpected end of file in box " + std::to_string(b) +
              " (vertex " + std::to_string(c) + " of 8 missing; NUM = " + std::to_string(num) + ")";
      return false;
    }
    if (c == 0)
      first_line = reader.line();
    if (tokens.size() != 3)
    {
      error = "line " + std::to_string(reader.line()) + ": expected 3 coordinates 'x y z' for vertex " +
              std::to_string(c) + " of box " + std::to_string(b) + ", got " + std::to_string(tokens.size()) +
              " values";
      return false;
    }
    for (int k = 0; k < 3; ++k)
    {
      double value = 0.0;
      if (!parseDouble(tokens[k], value))
      {
        error = "line " + std::to_string(reader.line()) + ": '" + tokens[k] + "' is not a finite number (vertex " +
                std::to_string(c) + " of box " + std::to_string(b) + ")";
        return false;
      }
      v[c][k] = value * scaling;
    }
  }
  return true;
}
}  // namespace

bool parseVertices(std::istream& in, double scaling, double relative_tolerance, std::vector<OrientedBox>& boxes,
                   std::string& error)
{
  boxes.clear();
  if (!(scaling > 0.0) || !std::isfinite(scaling))
  {
    error = "scaling must be a finite number > 0";
    return false;
  }
  LineReader reader(in);
  std::vector<std::string> tokens;
  long num = -1;
  if (!readBoxCount(reader, tokens, num, error))
    return false;
  boxes.reserve(static_cast<std::size_t>(num));
  for (long b = 0; b < num; ++b)
  {
    Eigen::Vector3d v[8];
    int first_line = 0;
    if (!readBoxVertices(reader, tokens, b, num, scaling, v, first_line, error))
      return false;
    OrientedBox box;
    const int code = makeBox(v, relative_tolerance, box);
    if (code != kSeparated)
    {
      error = "lines " + std::to_string(first_line) + "-" + std::to_string(reader.line()) + ": box " +
              std::to_string(b) +
              " is not a rectangular box with vertices in the order v0, v0+x, v0+x+z, v0+z, v0+y, v0+x+y, "
              "v0+x+y+z, v0+y+z (" +
              codeName(code) + ")";
      return false;
    }
    boxes.push_back(box);
  }
  if (reader.nextLine(tokens))
  {
    error = "line " + std::to_string(reader.line()) + ": unexpected data after the " + std::to_string(num) +
            " boxes declared by NUM";
    return false;
  }
  return true;
}

bool loadVerticesFile(const std::string& path, double scaling, double relative_tolerance,
                      std::vector<OrientedBox>& boxes, std::string& error)
{
  std::ifstream in(path);
  if (!in)
  {
    error = path + ": cannot open file";
    return false;
  }
  if (!parseVertices(in, scaling, relative_tolerance, boxes, error))
  {
    error = path + ": " + error;
    return false;
  }
  return true;
}

}  // namespace saras_collision
