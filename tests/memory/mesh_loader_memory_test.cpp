// loadMesh's heap against the file's size and the mesh it yields (counting_heap.h): a torus of 40,000
// triangles written in every format gpucol reads, triangles and quads, text and binary. What a load holds at
// its peak above what it keeps (the file's bytes, the reader's arrays, welding, triangulation, the mesh
// report) must stay within a small multiple of the file plus the mesh; docs/using-gpucol.md, "Mesh files", quotes the bound.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "counting_heap.h"
#include "gpucol/triangle_mesh.h"

namespace {

using gpucol::test::HeapOfStep;
using gpucol::test::measureHeap;

/// A torus of `ring` x `tube` quads: vertex (i, j) at index i * tube + j.
struct Torus {
  int ring = 200, tube = 100;
  std::vector<std::array<float, 3>> vertices;
  std::vector<std::array<std::uint32_t, 4>> quads;  ///< Counter-clockwise seen from outside.
  Torus() {
    for (int i = 0; i < ring; ++i) {
      for (int j = 0; j < tube; ++j) {
        const double u = 2 * M_PI * i / ring, v = 2 * M_PI * j / tube, r = 1 + 0.3 * std::cos(v);
        vertices.push_back({float(r * std::cos(u)), float(r * std::sin(u)), float(0.3 * std::sin(v))});
        const auto at = [&](int a, int b) { return std::uint32_t((a % ring) * tube + b % tube); };
        quads.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    }
  }
  /// The quad's two triangles' corners.
  static std::array<std::uint32_t, 6> split(const std::array<std::uint32_t, 4>& q) {
    return {q[0], q[1], q[2], q[0], q[2], q[3]};
  }
};

std::string text(float v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.9g", double(v));
  return buffer;
}

std::string asciiPly(const Torus& t, bool quads) {
  std::string out = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(t.vertices.size()) +
                    "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
                    std::to_string(t.quads.size() * (quads ? 1 : 2)) +
                    "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& v : t.vertices) out += text(v[0]) + " " + text(v[1]) + " " + text(v[2]) + "\n";
  for (const auto& q : t.quads) {
    if (quads) {
      out += "4 " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) + " " +
             std::to_string(q[3]) + "\n";
      continue;
    }
    const auto s = Torus::split(q);
    for (int k = 0; k < 6; k += 3)
      out += "3 " + std::to_string(s[k]) + " " + std::to_string(s[k + 1]) + " " + std::to_string(s[k + 2]) +
             "\n";
  }
  return out;
}

std::string binaryPly(const Torus& t) {
  std::string out =
      "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(t.vertices.size()) +
      "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
      std::to_string(2 * t.quads.size()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const auto& v : t.vertices) out.append(reinterpret_cast<const char*>(v.data()), 12);
  for (const auto& q : t.quads) {
    const auto s = Torus::split(q);
    for (int k = 0; k < 6; k += 3) {
      out += char(3);
      out.append(reinterpret_cast<const char*>(&s[std::size_t(k)]), 12);
    }
  }
  return out;
}

std::string off(const Torus& t) {
  std::string out =
      "OFF\n" + std::to_string(t.vertices.size()) + " " + std::to_string(t.quads.size()) + " 0\n";
  for (const auto& v : t.vertices) out += text(v[0]) + " " + text(v[1]) + " " + text(v[2]) + "\n";
  for (const auto& q : t.quads)
    out += "4 " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) + " " +
           std::to_string(q[3]) + "\n";
  return out;
}

std::string obj(const Torus& t, bool quads) {
  std::string out;
  for (const auto& v : t.vertices) out += "v " + text(v[0]) + " " + text(v[1]) + " " + text(v[2]) + "\n";
  for (const auto& q : t.quads) {
    if (quads) {
      out += "f " + std::to_string(q[0] + 1) + " " + std::to_string(q[1] + 1) + " " +
             std::to_string(q[2] + 1) + " " + std::to_string(q[3] + 1) + "\n";
      continue;
    }
    const auto s = Torus::split(q);
    for (int k = 0; k < 6; k += 3)
      out += "f " + std::to_string(s[k] + 1) + " " + std::to_string(s[k + 1] + 1) + " " +
             std::to_string(s[k + 2] + 1) + "\n";
  }
  return out;
}

std::string stl(const Torus& t, bool binary) {
  std::string out = binary ? std::string(80, ' ') : "solid torus\n";
  if (binary) {
    const std::uint32_t count = std::uint32_t(2 * t.quads.size());
    out.append(reinterpret_cast<const char*>(&count), 4);
  }
  for (const auto& q : t.quads) {
    const auto s = Torus::split(q);
    for (int k = 0; k < 6; k += 3) {
      if (binary) {
        out.append(12, '\0');
        for (int c = 0; c < 3; ++c)
          out.append(reinterpret_cast<const char*>(t.vertices[s[std::size_t(k + c)]].data()), 12);
        out.append(2, '\0');
        continue;
      }
      out += "facet normal 0 0 0\nouter loop\n";
      for (int c = 0; c < 3; ++c) {
        const auto& v = t.vertices[s[std::size_t(k + c)]];
        out += "vertex " + text(v[0]) + " " + text(v[1]) + " " + text(v[2]) + "\n";
      }
      out += "endloop\nendfacet\n";
    }
  }
  if (!binary) out += "endsolid torus\n";
  return out;
}

TEST(MeshLoaderMemory, PeakStaysWithinASmallMultipleOfTheFileAndTheMesh) {
  // Peak above the start <= kFile * file bytes + kMesh * bytes the mesh keeps.
  constexpr double kFile = 2.0, kMesh = 4.0;
  const Torus torus;
  const std::string dir = (std::filesystem::temp_directory_path() /
                           ("gpucol_loader_memory_" + std::to_string(std::random_device()())))
                              .string();
  std::filesystem::create_directory(dir);
  const std::vector<std::pair<std::string, std::string>> files = {
      {"binary.ply", binaryPly(torus)},     {"triangles.ply", asciiPly(torus, false)},
      {"quads.ply", asciiPly(torus, true)}, {"quads.off", off(torus)},
      {"triangles.obj", obj(torus, false)}, {"quads.obj", obj(torus, true)},
      {"binary.stl", stl(torus, true)},     {"ascii.stl", stl(torus, false)}};
  for (const auto& [name, bytes] : files) {
    const std::string path = dir + "/" + name;
    std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    std::size_t triangles = 0;
    const HeapOfStep heap = measureHeap([&] {
      const gpucol::TriangleMesh mesh = gpucol::loadMesh(path);
      triangles = mesh.triangleCount();
      EXPECT_EQ(mesh.vertexCount(), torus.vertices.size()) << name;
      EXPECT_TRUE(mesh.report().closed) << name;
    });
    EXPECT_EQ(triangles, 2 * torus.quads.size()) << name;
    // What the mesh keeps: its arrays and report.
    std::size_t meshBytes = 0;
    {
      const std::size_t before = gpucol::test::heapLive();
      const gpucol::TriangleMesh mesh = gpucol::loadMesh(path);
      meshBytes = gpucol::test::heapLive() - before;
    }
    const double bound = kFile * double(bytes.size()) + kMesh * double(meshBytes);
    std::printf(
        "%-14s file %8zu B, mesh %8zu B, peak %9td B = %.2f x file + %.2f x mesh at most (bound %.0f)\n",
        name.c_str(), bytes.size(), meshBytes, heap.mark, double(heap.mark) / double(bytes.size()),
        double(heap.mark) / double(meshBytes), bound);
    EXPECT_LE(double(heap.mark), bound) << name;
    EXPECT_EQ(heap.kept, 0) << name << ": the load leaves nothing behind";
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
