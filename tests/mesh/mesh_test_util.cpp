#include "mesh_test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

namespace gpucol::test {

MeshArrays boxArrays(std::array<double, 3> h, std::array<double, 3> c, int n) {
  MeshArrays out;
  std::map<std::array<int, 3>, std::uint32_t> ids;  // lattice point -> vertex, so faces share corners
  const auto vertex = [&](std::array<int, 3> g) {
    auto [it, inserted] = ids.emplace(g, std::uint32_t(ids.size()));
    if (inserted) {
      for (int k = 0; k < 3; ++k) out.xyz.push_back(float(c[k] + h[k] * (2.0 * g[k] / n - 1.0)));
    }
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          std::array<std::uint32_t, 4> q;
          const int di[4] = {0, 1, 1, 0}, dj[4] = {0, 0, 1, 1};
          for (int k = 0; k < 4; ++k) {
            std::array<int, 3> g{};
            g[axis] = side * n;
            g[u] = i + di[k];
            g[v] = j + dj[k];
            q[k] = vertex(g);
          }
          // (u, v, axis) is right-handed, so u then v is counter-clockwise seen from +axis.
          if (side == 1) {
            out.indices.insert(out.indices.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
          } else {
            out.indices.insert(out.indices.end(), {q[0], q[2], q[1], q[0], q[3], q[2]});
          }
        }
      }
    }
  }
  return out;
}

MeshArrays icosphereArrays(double r, int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<std::array<double, 3>> p = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                          {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                          {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<std::uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  const auto normalise = [](std::array<double, 3> v) {
    const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    return std::array<double, 3>{v[0] / l, v[1] / l, v[2] / l};
  };
  for (auto& v : p) v = normalise(v);
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    const auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      auto [it, inserted] = mid.emplace(key, std::uint32_t(p.size()));
      if (inserted) p.push_back(normalise({p[a][0] + p[b][0], p[a][1] + p[b][1], p[a][2] + p[b][2]}));
      return it->second;
    };
    std::vector<std::array<std::uint32_t, 3>> next;
    for (const auto& tri : f) {
      const std::uint32_t ab = midpoint(tri[0], tri[1]), bc = midpoint(tri[1], tri[2]),
                          ca = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], ab, ca});
      next.push_back({tri[1], bc, ab});
      next.push_back({tri[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    f = next;
  }
  MeshArrays out;
  for (const auto& v : p) {
    for (double x : v) out.xyz.push_back(float(r * x));
  }
  for (const auto& tri : f) out.indices.insert(out.indices.end(), tri.begin(), tri.end());
  return out;
}

std::array<double, 9> axisAngle(std::array<double, 3> axis, double angle) {
  const double l = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  const double x = axis[0] / l, y = axis[1] / l, z = axis[2] / l;
  const double c = std::cos(angle), s = std::sin(angle), C = 1 - c;
  return {x * x * C + c,     x * y * C - z * s, x * z * C + y * s, y * x * C + z * s, y * y * C + c,
          y * z * C - x * s, z * x * C - y * s, z * y * C + x * s, z * z * C + c};
}

TempDir::TempDir() {
  std::random_device device;
  const std::filesystem::path base = std::filesystem::temp_directory_path();
  for (;;) {
    const std::filesystem::path candidate = base / ("gpucol_mesh_test_" + std::to_string(device()));
    if (std::filesystem::create_directory(candidate)) {
      m_path = candidate.string();
      return;
    }
  }
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(m_path, ec);
}

std::string TempDir::file(const std::string& name) const {
  return (std::filesystem::path(m_path) / name).string();
}

std::string TempDir::write(const std::string& name, const std::string& bytes) const {
  const std::string path = file(name);
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  return path;
}

std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

MeshArrays readReferencePly(const std::string& path) {
  const std::string bytes = readBytes(path);
  const std::size_t body = bytes.find("end_header\n");
  MeshArrays out;
  if (body == std::string::npos) {
    ADD_FAILURE() << path << ": no end_header";
    return out;
  }
  std::istringstream header(bytes.substr(0, body));
  std::size_t vertices = 0, faces = 0;
  for (std::string line; std::getline(header, line);) {
    std::istringstream in(line);
    std::string keyword, name;
    in >> keyword >> name;
    if (keyword == "format") {
      EXPECT_EQ(name, "binary_little_endian") << path;
    }
    if (keyword == "element" && name == "vertex") in >> vertices;
    if (keyword == "element" && name == "face") in >> faces;
  }
  std::size_t offset = body + std::strlen("end_header\n");
  if (bytes.size() != offset + 12 * vertices + 13 * faces) {
    ADD_FAILURE() << path << ": not the documented layout";
    return out;
  }
  out.xyz.resize(3 * vertices);
  std::memcpy(out.xyz.data(), bytes.data() + offset, 12 * vertices);
  offset += 12 * vertices;
  for (std::size_t f = 0; f < faces; ++f, offset += 13) {
    EXPECT_EQ(bytes[offset], 3) << path << " face " << f;
    std::int32_t v[3];
    std::memcpy(v, bytes.data() + offset + 1, 12);
    for (std::int32_t i : v) out.indices.push_back(std::uint32_t(i));
  }
  return out;
}

}  // namespace gpucol::test
