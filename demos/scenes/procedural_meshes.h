#pragma once

#include <gpucol/triangle_mesh.h>

namespace gpucol::scenes {

/// A closed box centred on the origin with half extents (hx, hy, hz); each face split into n × n quads.
TriangleMesh makeBox(float hx, float hy, float hz, int subdivisions = 1);

/// A closed sphere of `radius` centred on the origin: an icosahedron subdivided `levels` times.
TriangleMesh makeIcosphere(float radius, int levels);

/// A closed torus about the z axis: ring radius `major`, tube radius `minor`, `ringSegments` × `tubeSegments`.
TriangleMesh makeTorus(float major, float minor, int ringSegments, int tubeSegments);

/// A closed bin, open at the top, as one watertight surface: a floor of `floorThickness` below y = 0 and walls
/// up to y = `height`, square, `outerHalf` from the centre outside and `innerHalf` inside.
TriangleMesh makeBin(float outerHalf, float innerHalf, float floorThickness, float height);

/// A closed, concave L-shaped prism: an L of arm length `size` and thickness `size / 3`, `depth` thick in z.
TriangleMesh makeLShape(float size, float depth);

/// A closed, concave plus-shaped prism in the xy plane: arms reaching `arm` from the centre along ±x and ±y,
/// `width` wide, `depth` thick in z; symmetric, so its centre of mass is the origin and its axes principal.
TriangleMesh makeCross(float arm, float width, float depth);

}  // namespace gpucol::scenes
