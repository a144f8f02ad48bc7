// GridBroadphase's rayTest and aabbTest through the query index against the same tests run on every box
// (btRayAabb2 on the grown bounds, the touching-counts overlap): varied scenes, rays with and without a cast
// box, along the axes, from inside boxes, with long and negative lambdas; boxes moving, appearing and
// vanishing between queries (few: the index keeps them aside; many: it is dropped and built again).
#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "gpucol/grid_broadphase.h"

namespace {

struct QueryBox {
  btVector3 lo, hi;
  btBroadphaseProxy* proxy = nullptr;
};

/// Collects the client ids a query reports, in report order.
struct Reported : btBroadphaseRayCallback {
  std::vector<int> ids;
  bool process(const btBroadphaseProxy* proxy) override {
    ids.push_back(int(reinterpret_cast<std::intptr_t>(proxy->m_clientObject)));
    return true;
  }
  void setRay(const btVector3& from, const btVector3& to) {
    // As btSingleRayCallback does in btCollisionWorld.cpp.
    const btVector3 dir = (to - from).normalized();
    m_rayDirectionInverse =
        btVector3(dir[0] == 0 ? BT_LARGE_FLOAT : 1 / dir[0], dir[1] == 0 ? BT_LARGE_FLOAT : 1 / dir[1],
                  dir[2] == 0 ? BT_LARGE_FLOAT : 1 / dir[2]);
    for (int a = 0; a < 3; ++a) m_signs[a] = m_rayDirectionInverse[a] < 0.0;
    m_lambda_max = dir.dot(to - from);
  }
};

enum class Scene { Uniform, Clustered, Mixed, Flat, Identical, Far, Negative };

const char* nameOf(Scene s) {
  switch (s) {
    case Scene::Uniform:
      return "uniform";
    case Scene::Clustered:
      return "clustered";
    case Scene::Mixed:
      return "mixed";
    case Scene::Flat:
      return "flat";
    case Scene::Identical:
      return "identical";
    case Scene::Far:
      return "far";
    case Scene::Negative:
      return "negative";
  }
  return "?";
}

/// A random box of the scene's kind.
void randomBox(Scene scene, std::mt19937& rng, QueryBox& b) {
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const float side = 60.0f;
  btVector3 c(side * (unit(rng) - 0.5f), side * (unit(rng) - 0.5f), side * (unit(rng) - 0.5f));
  btVector3 h(0.2f + unit(rng), 0.2f + unit(rng), 0.2f + unit(rng));
  switch (scene) {
    case Scene::Uniform:
      break;
    case Scene::Clustered: {
      const int cluster = int(unit(rng) * 8);
      c = btVector3(float(cluster * 7 % 5) * 12.0f, float(cluster % 3) * 15.0f, float(cluster % 2) * 20.0f) +
          btVector3(unit(rng), unit(rng), unit(rng)) * 4.0f;
      h *= 0.3f;
      break;
    }
    case Scene::Mixed:
      h = btVector3(0.1f, 0.1f, 0.1f) + btVector3(unit(rng), unit(rng), unit(rng)) * 1.9f;
      if (unit(rng) < 0.004f) h = btVector3(40.0f, 40.0f * unit(rng), 2.0f);  // huge: kept out of the cells
      if (unit(rng) < 0.02f) h.setX(15.0f);                                   // long, still filed
      break;
    case Scene::Flat:
      c.setZ(0.0f), h.setZ(0.0f);
      break;
    case Scene::Identical:
      if (unit(rng) < 0.3f) c = btVector3(1, 2, 3), h = btVector3(0.5f, 0.5f, 0.5f);
      break;
    case Scene::Far:
      c += btVector3(1e6f, -1e6f, 1e6f);
      break;
    case Scene::Negative:
      c = c * 0.5f - btVector3(950.0f, 950.0f, 950.0f);
      break;
  }
  b.lo = c - h;
  b.hi = c + h;
}

/// The ids the scan reports: every live box whose grown bounds the ray hits (btRayAabb2, as the broad
/// phase calls it), and every live box overlapping a query box.
std::vector<int> scanRay(const std::vector<QueryBox>& boxes, const btVector3& from, const Reported& ray,
                         const btVector3& castLo, const btVector3& castHi) {
  std::vector<int> ids;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    if (!boxes[i].proxy) continue;
    const btVector3 bounds[2] = {boxes[i].lo - castHi, boxes[i].hi - castLo};
    btScalar tmin = 0;
    if (btRayAabb2(from, ray.m_rayDirectionInverse, ray.m_signs, bounds, tmin, 0, ray.m_lambda_max))
      ids.push_back(int(i));
  }
  return ids;
}

std::vector<int> scanBox(const std::vector<QueryBox>& boxes, const btVector3& lo, const btVector3& hi) {
  std::vector<int> ids;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const QueryBox& b = boxes[i];
    if (b.proxy && b.lo.x() <= hi.x() && b.hi.x() >= lo.x() && b.lo.y() <= hi.y() && b.hi.y() >= lo.y() &&
        b.lo.z() <= hi.z() && b.hi.z() >= lo.z())
      ids.push_back(int(i));
  }
  return ids;
}

/// Sorted copy with a check that nothing was reported twice.
std::vector<int> sortedOnce(std::vector<int> ids) {
  std::sort(ids.begin(), ids.end());
  EXPECT_TRUE(std::adjacent_find(ids.begin(), ids.end()) == ids.end()) << "a proxy reported twice";
  return ids;
}

/// Runs `count` random ray and box queries on `grid` and checks each against the scan; returns the hits.
std::size_t checkQueries(gpucol::GridBroadphase& grid, const std::vector<QueryBox>& boxes, std::mt19937& rng,
                         int count, const std::string& where) {
  btVector3 lo = boxes[0].lo, hi = boxes[0].hi;
  for (const QueryBox& b : boxes) lo.setMin(b.lo), hi.setMax(b.hi);
  const btVector3 size = hi - lo;
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  auto inScene = [&] {
    return lo - 0.1f * size + btVector3(unit(rng), unit(rng), unit(rng)) * (1.2f * size);
  };
  std::size_t hits = 0;
  for (int q = 0; q < count; ++q) {
    btVector3 from = inScene(), to = inScene();
    if (q % 7 == 0) to = from + btVector3(0, 0, size.z() * (unit(rng) - 0.5f));  // along an axis
    if (q % 11 == 0) from = boxes[std::size_t(q) % boxes.size()].lo;             // from a box's corner
    btVector3 castLo(0, 0, 0), castHi(0, 0, 0);
    if (q % 3 == 1) {
      castLo = -btVector3(unit(rng), unit(rng), unit(rng)) * 2.0f;
      castHi = btVector3(unit(rng), unit(rng), unit(rng)) * 2.0f;
    }
    Reported ray;
    ray.setRay(from, to);
    if (q % 13 == 0) ray.m_lambda_max = -ray.m_lambda_max * unit(rng);  // a negative lambda
    if (q % 17 == 0) ray.m_lambda_max = 1e7f;                           // through everything
    const Reported fresh = ray;
    grid.rayTest(from, to, ray, castLo, castHi);
    const std::vector<int> expectRay = scanRay(boxes, from, fresh, castLo, castHi);
    if (sortedOnce(ray.ids) != expectRay) {
      ADD_FAILURE() << where << ", ray " << q << ": " << ray.ids.size() << " reported, " << expectRay.size()
                    << " expected";
      return hits;
    }
    hits += expectRay.size();

    const btVector3 c = inScene();
    const btVector3 h = btVector3(unit(rng), unit(rng), unit(rng)) * (q % 19 == 0 ? size.length() : 3.0f);
    btVector3 qlo = c - h, qhi = c + h;
    if (q % 23 == 0) std::swap(qlo, qhi);  // inverted: overlapped by boxes spanning [qhi, qlo]
    Reported box;
    grid.aabbTest(qlo, qhi, box);
    const std::vector<int> expectBox = scanBox(boxes, qlo, qhi);
    if (sortedOnce(box.ids) != expectBox) {
      ADD_FAILURE() << where << ", box " << q << ": " << box.ids.size() << " reported, " << expectBox.size()
                    << " expected";
      return hits;
    }
    hits += expectBox.size();
  }
  return hits;
}

TEST(GridBroadphaseQueries, IndexedQueriesReportWhatTheScanReports) {
  for (Scene scene : {Scene::Uniform, Scene::Clustered, Scene::Mixed, Scene::Flat, Scene::Identical,
                      Scene::Far, Scene::Negative}) {
    SCOPED_TRACE(nameOf(scene));
    std::mt19937 rng(41 + int(scene));
    gpucol::GridBroadphase grid;
    std::vector<QueryBox> boxes(3000);
    auto create = [&](std::size_t i) {
      randomBox(scene, rng, boxes[i]);
      boxes[i].proxy = grid.createProxy(boxes[i].lo, boxes[i].hi, BOX_SHAPE_PROXYTYPE,
                                        reinterpret_cast<void*>(std::intptr_t(i)), 1, -1, nullptr);
    };
    auto move = [&](std::size_t i) {
      randomBox(scene, rng, boxes[i]);
      grid.setAabb(boxes[i].proxy, boxes[i].lo, boxes[i].hi, nullptr);
    };
    for (std::size_t i = 0; i < boxes.size(); ++i) create(i);
    grid.calculateOverlappingPairs(nullptr);
    std::size_t hits = checkQueries(grid, boxes, rng, 300, "fresh");
    const gpucol::GridBroadphaseQueryStats first = grid.queryStats();
    EXPECT_EQ(first.indexBuilds, 1u);
    EXPECT_GT(first.indexed, 500u) << "the index should answer most queries";
    EXPECT_GT(first.indexBytes, 0u);

    // A few boxes move: the index keeps them aside and stays.
    for (std::size_t i = 0; i < boxes.size(); i += 97) move(i);
    hits += checkQueries(grid, boxes, rng, 150, "few moved");
    // Some vanish and new ones take their slots (after a search, as in a world).
    for (std::size_t i = 5; i < boxes.size(); i += 211) {
      grid.destroyProxy(boxes[i].proxy, nullptr);
      boxes[i].proxy = nullptr;
    }
    hits += checkQueries(grid, boxes, rng, 100, "few destroyed");
    grid.calculateOverlappingPairs(nullptr);
    for (std::size_t i = 5; i < boxes.size(); i += 211) create(i);
    hits += checkQueries(grid, boxes, rng, 100, "slots reused");
    EXPECT_EQ(grid.queryStats().indexBuilds, 1u) << "few changes should keep the index";

    // Half the boxes move: the index refiles those it can, keeps the others aside or is dropped and built
    // again; the answers stay exact either way.
    for (std::size_t i = 0; i < boxes.size(); i += 2) move(i);
    grid.calculateOverlappingPairs(nullptr);
    hits += checkQueries(grid, boxes, rng, 150, "half moved");
    // Every box moves three times: the index moves each box it filed by its min corner to its new cell and
    // keeps the others aside (dropped and built again when they are too many).
    for (int round = 0; round < 3; ++round) {
      for (std::size_t i = 0; i < boxes.size(); ++i) move(i);
      grid.calculateOverlappingPairs(nullptr);
      hits += checkQueries(grid, boxes, rng, 50, "all moved, round " + std::to_string(round));
    }
    // Every box grows to three times its size, beyond what the index reaches back by: it cannot follow
    // them, so it is dropped, queries scan, then it is built again.
    const gpucol::GridBroadphaseQueryStats beforeGrowth = grid.queryStats();
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      const btVector3 c = (boxes[i].lo + boxes[i].hi) * 0.5f, h = (boxes[i].hi - boxes[i].lo) * 1.5f;
      boxes[i].lo = c - h, boxes[i].hi = c + h;
      grid.setAabb(boxes[i].proxy, boxes[i].lo, boxes[i].hi, nullptr);
    }
    grid.calculateOverlappingPairs(nullptr);
    hits += checkQueries(grid, boxes, rng, 150, "all grown");
    const gpucol::GridBroadphaseQueryStats last = grid.queryStats();
    EXPECT_GT(last.indexBuilds, beforeGrowth.indexBuilds) << "boxes it cannot follow should drop the index";
    EXPECT_GE(last.scans, beforeGrowth.scans + 6) << "queries after the drop should scan before the rebuild";
    EXPECT_GT(hits, 2000u) << "queries should hit something";
  }
}

TEST(GridBroadphaseQueries, FewProxiesOrFewQueriesScan) {
  gpucol::GridBroadphase grid;
  std::mt19937 rng(3);
  std::vector<QueryBox> boxes(200);
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    randomBox(Scene::Uniform, rng, boxes[i]);
    boxes[i].proxy = grid.createProxy(boxes[i].lo, boxes[i].hi, BOX_SHAPE_PROXYTYPE,
                                      reinterpret_cast<void*>(std::intptr_t(i)), 1, -1, nullptr);
  }
  checkQueries(grid, boxes, rng, 50, "200 proxies");
  EXPECT_EQ(grid.queryStats().indexBuilds, 0u) << "no index below its proxy threshold";
  EXPECT_EQ(grid.queryStats().indexBytes, 0u);

  // Above the threshold, a world that moves every box between every four queries (two rays, two boxes)
  // never builds one.
  boxes.resize(2000);
  for (std::size_t i = 200; i < boxes.size(); ++i) {
    randomBox(Scene::Uniform, rng, boxes[i]);
    boxes[i].proxy = grid.createProxy(boxes[i].lo, boxes[i].hi, BOX_SHAPE_PROXYTYPE,
                                      reinterpret_cast<void*>(std::intptr_t(i)), 1, -1, nullptr);
  }
  for (int step = 0; step < 20; ++step) {
    for (QueryBox& b : boxes) {
      b.lo += btVector3(0.01f, 0, 0), b.hi += btVector3(0.01f, 0, 0);
      grid.setAabb(b.proxy, b.lo, b.hi, nullptr);
    }
    grid.calculateOverlappingPairs(nullptr);
    checkQueries(grid, boxes, rng, 2, "moving world");
  }
  EXPECT_EQ(grid.queryStats().indexBuilds, 0u) << "four queries per change should never pay for an index";
}

// A world where every box drifts every frame and each frame asks many queries: the index files the boxes
// grown once the boxes moved one away, so it outlives the drift; boxes that leave their grown box are kept
// aside and, from the next step, filed in an index of moved boxes. Every answer stays the scan's.
TEST(GridBroadphaseQueries, DriftingWorldsKeepTheirIndexAndItsAnswers) {
  gpucol::GridBroadphase grid;
  std::mt19937 rng(8);
  std::vector<QueryBox> boxes(3000);
  std::vector<btVector3> velocity(boxes.size());
  std::uniform_real_distribution<float> dir(-1, 1);
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    randomBox(Scene::Uniform, rng, boxes[i]);
    boxes[i].proxy = grid.createProxy(boxes[i].lo, boxes[i].hi, BOX_SHAPE_PROXYTYPE,
                                      reinterpret_cast<void*>(std::intptr_t(i)), 1, -1, nullptr);
    // Most drift slowly; one in 50 fast enough to leave its grown box within a frame or two.
    const float speed = (i % 50 == 0 ? 0.1f : 0.004f) * (boxes[i].hi - boxes[i].lo).x();
    velocity[i] = btVector3(dir(rng), dir(rng), dir(rng)) * speed;
  }
  grid.calculateOverlappingPairs(nullptr);
  const int frames = 40;
  for (int frame = 0; frame < frames; ++frame) {
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      boxes[i].lo += velocity[i], boxes[i].hi += velocity[i];
      grid.setAabb(boxes[i].proxy, boxes[i].lo, boxes[i].hi, nullptr);
    }
    grid.calculateOverlappingPairs(nullptr);
    checkQueries(grid, boxes, rng, 30, "frame " + std::to_string(frame));
    if (::testing::Test::HasFailure()) return;
  }
  const gpucol::GridBroadphaseQueryStats stats = grid.queryStats();
  EXPECT_LE(stats.indexBuilds, 8u) << "drifting boxes should not cost an index per frame";
  EXPECT_GT(stats.indexed, stats.scans * 4) << "the index should answer most queries";
}

TEST(GridBroadphaseQueries, MovedBoxesAreRefiledWhereverTheyGo) {
  // Boxes of one size, indexed once; then a third of them jump, some far beyond the grid's cells (filed in
  // its edge cells, found by queries out there), and the index follows them without a rebuild.
  for (float jump : {3.0f, 200.0f}) {
    SCOPED_TRACE(jump);
    gpucol::GridBroadphase grid;
    std::mt19937 rng(12);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::vector<QueryBox> boxes(2000);
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      const btVector3 c(60 * unit(rng), 60 * unit(rng), 60 * unit(rng));
      boxes[i].lo = c - btVector3(0.5f, 0.5f, 0.5f), boxes[i].hi = c + btVector3(0.5f, 0.5f, 0.5f);
      boxes[i].proxy = grid.createProxy(boxes[i].lo, boxes[i].hi, BOX_SHAPE_PROXYTYPE,
                                        reinterpret_cast<void*>(std::intptr_t(i)), 1, -1, nullptr);
    }
    grid.calculateOverlappingPairs(nullptr);
    checkQueries(grid, boxes, rng, 100, "fresh");
    for (std::size_t i = 0; i < boxes.size(); i += 3) {
      const btVector3 by(jump * (unit(rng) - 0.5f), jump * (unit(rng) - 0.5f), jump * (unit(rng) - 0.5f));
      boxes[i].lo += by, boxes[i].hi += by;
      grid.setAabb(boxes[i].proxy, boxes[i].lo, boxes[i].hi, nullptr);
    }
    checkQueries(grid, boxes, rng, 200, "jumped");
    grid.calculateOverlappingPairs(nullptr);
    checkQueries(grid, boxes, rng, 100, "jumped, after a step");
    // Then every box jumps, three times: cells fill beyond what they held at the build and empty again.
    for (int round = 0; round < 3; ++round) {
      for (QueryBox& b : boxes) {
        const btVector3 by(jump * (unit(rng) - 0.5f), jump * (unit(rng) - 0.5f), jump * (unit(rng) - 0.5f));
        b.lo += by, b.hi += by;
        grid.setAabb(b.proxy, b.lo, b.hi, nullptr);
      }
      grid.calculateOverlappingPairs(nullptr);
      checkQueries(grid, boxes, rng, 100, "all jumped, round " + std::to_string(round));
    }
    EXPECT_EQ(grid.queryStats().indexBuilds, 1u) << "boxes of the filed size should be refiled";
  }
}

}  // namespace
