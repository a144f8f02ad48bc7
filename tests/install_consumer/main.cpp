// Uses the installed gpucol: builds two meshes from arrays, collides them, and checks the answer.
#include <gpucol/gpucol.h>

#include <iostream>
#include <memory>

int main() {
  // A unit tetrahedron, counter-clockwise seen from outside.
  std::vector<float> xyz = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::vector<std::uint32_t> indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  auto mesh = std::make_shared<const gpucol::TriangleMesh>(gpucol::TriangleMesh::fromArrays(xyz, indices));
  gpucol::MeshShape a(mesh), b(mesh);
  btTransform ta = btTransform::getIdentity(), tb = btTransform::getIdentity();
  tb.setOrigin(btVector3(0.2f, 0.2f, 0.2f));
  const gpucol::MeshPairResult result = gpucol::collideMeshes(a, ta, b, tb);
  if (result.intersectingPairs.empty()) {
    std::cerr << "install check: overlapping tetrahedra gave no intersecting triangle pair\n";
    return 1;
  }
  std::cout << "install check: find_package(gpucol) works; " << result.intersectingPairs.size()
            << " intersecting triangle pairs, " << result.reducedContacts.size() << " reduced contacts\n";
  return 0;
}
