/**
 * @file vertices_file.h
 * @brief Parser of the forbidden-region file of D7.2 Section 6.1.
 *
 * Format (plain text, whitespace separated, '#' starts a comment to the end of the line):
 *   NUM                    number of boxes (integer >= 0)
 *   x y z                  8 lines per box, one vertex per line, in the order of
 *   ...                    saras_collision/geometry.h (v0 .. v7), in file units
 * Every coordinate is multiplied by `scaling` (file unit -> metres). Anything else (missing or
 * extra numbers, non-numeric text, NaN, a non-rectangular box, trailing data) is an error
 * naming the file line.
 */
#ifndef SARAS_COLLISION_VERTICES_FILE_H
#define SARAS_COLLISION_VERTICES_FILE_H

#include <istream>
#include <string>
#include <vector>

#include "saras_collision/geometry.h"

namespace saras_collision
{
/**
 * @brief Parse boxes from a stream.
 * @param in the text; @param scaling file unit -> metres (> 0)
 * @param relative_tolerance box check tolerance (see makeBox)
 * @param[out] boxes the boxes in the file frame [m]
 * @param[out] error "line N: reason" on failure
 * @return true on success
 */
bool parseVertices(std::istream& in, double scaling, double relative_tolerance, std::vector<OrientedBox>& boxes,
                   std::string& error);

/// Same, from a file; the error starts with the file name.
bool loadVerticesFile(const std::string& path, double scaling, double relative_tolerance,
                      std::vector<OrientedBox>& boxes, std::string& error);

}  // namespace saras_collision

#endif  // SARAS_COLLISION_VERTICES_FILE_H
