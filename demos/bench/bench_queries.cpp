// gpucol-bench queries: rayTest and aabbTest of gpucol::GridBroadphase through its query index, and by
// testing every proxy (GridBroadphaseOptions::queryIndex off), beside btDbvtBroadphase on the same boxes:
// median microseconds per query, hits per query, what building the index costs against a scan (the
// ski-rental rule's kScansBeforeIndex) and the bytes it holds.
#include <btBulletCollisionCommon.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bench_commands.h"
#include "bench_stats.h"
#include "bullet/grid_broadphase_options.h"
#include "gpucol/grid_broadphase.h"

namespace gpucol::bench {
namespace {

/// Boxes at a density of about one per 8 unit volumes (as `gpucol-bench broadphase`): unit boxes
/// ("uniform"), or half extents from 0.1 to 2, few large, plus one huge box per 20,000 ("mixed").
struct QueryScene {
  std::vector<btVector3> lo, hi;
  float side = 0;
};

QueryScene makeScene(const std::string& name, std::size_t n, std::uint32_t seed) {
  QueryScene s;
  s.side = std::cbrt(float(n) * 8.0f);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(0, s.side), u(0, 1);
  for (std::size_t i = 0; i < n; ++i) {
    const btVector3 c(pos(rng), pos(rng), pos(rng));
    btVector3 h(0.5f, 0.5f, 0.5f);
    if (name == "mixed") {
      const float r = 0.1f + 1.9f * std::pow(u(rng), 4.0f);
      h = btVector3(r, 0.1f + 1.9f * std::pow(u(rng), 4.0f), r);
      if (i < std::max<std::size_t>(1, n / 20000)) h = btVector3(0.1f, 0.1f, 0.1f) * s.side;
    }
    s.lo.push_back(c - h), s.hi.push_back(c + h);
  }
  return s;
}

/// One query: a ray (with a cast box for sweeps) or a box.
struct Query {
  btVector3 from, to, castLo, castHi;
  bool isBox = false;
};

/// Query kinds: short rays (10 units: a wheel's or a sensor's), long rays (across the scene: picking),
/// sweeps (short rays carrying a unit box: convexSweepTest), boxes (half extent 2: ghost objects).
std::vector<Query> makeQueries(const std::string& kind, const QueryScene& scene, int count,
                               std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(0, scene.side), dir(-1, 1);
  std::vector<Query> queries;
  for (int i = 0; i < count; ++i) {
    Query q;
    q.from = btVector3(pos(rng), pos(rng), pos(rng));
    btVector3 d(dir(rng), dir(rng), dir(rng));
    if (d.length2() < 1e-6f) d = btVector3(0, -1, 0);
    d.normalize();
    q.castLo = q.castHi = btVector3(0, 0, 0);
    if (kind == "long") {
      q.from = btVector3(-1, pos(rng), pos(rng));
      q.to = btVector3(scene.side + 1, pos(rng), pos(rng));
    } else {
      q.to = q.from + d * 10.0f;
    }
    if (kind == "sweep") q.castLo = btVector3(-0.5f, -0.5f, -0.5f), q.castHi = btVector3(0.5f, 0.5f, 0.5f);
    if (kind == "box") {
      q.isBox = true;
      q.castLo = q.from - btVector3(2, 2, 2), q.castHi = q.from + btVector3(2, 2, 2);
    }
    queries.push_back(q);
  }
  return queries;
}

/// Counts what a query reports; set up as btCollisionWorld's ray callback does.
struct CountHits : btBroadphaseRayCallback {
  std::size_t hits = 0;
  bool process(const btBroadphaseProxy*) override {
    ++hits;
    return true;
  }
  void aim(const btVector3& from, const btVector3& to) {
    const btVector3 d = (to - from).normalized();
    m_rayDirectionInverse =
        btVector3(d[0] == 0 ? BT_LARGE_FLOAT : 1 / d[0], d[1] == 0 ? BT_LARGE_FLOAT : 1 / d[1],
                  d[2] == 0 ? BT_LARGE_FLOAT : 1 / d[2]);
    for (int a = 0; a < 3; ++a) m_signs[a] = m_rayDirectionInverse[a] < 0.0;
    m_lambda_max = d.dot(to - from);
  }
};

/// Runs every query once on `bp`; returns the hits.
std::size_t runQueries(btBroadphaseInterface& bp, const std::vector<Query>& queries) {
  std::size_t hits = 0;
  for (const Query& q : queries) {
    CountHits c;
    if (q.isBox) {
      bp.aabbTest(q.castLo, q.castHi, c);
    } else {
      c.aim(q.from, q.to);
      bp.rayTest(q.from, q.to, c, q.castLo, q.castHi);
    }
    hits += c.hits;
  }
  return hits;
}

struct Options {
  std::vector<std::size_t> sizes{10000, 100000};
  std::vector<std::string> scenes{"uniform", "mixed"};
  int queries = 1000;
  int runs = 5;
  int movingFrames = 0;                  // > 0: the moving-world frames instead of the static queries
  std::vector<float> speeds{0.01f, 0.2f};  // box sizes per frame every box moves, for the moving world
};

/// A frame of a world where every body moves: every box moved along its own direction by `speed` (its
/// velocity reversed where it would leave the scene), setAabb of every proxy and calculateOverlappingPairs,
/// then the frame's rays. Returns the milliseconds of the rays alone, and of the frame's broad-phase work.
struct MovingWorld {
  MovingWorld(const QueryScene& scene, float speed, std::uint32_t seed)
      : lo(scene.lo), hi(scene.hi), side(scene.side), dispatcher(&configuration) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> dir(-1, 1);
    for (std::size_t i = 0; i < lo.size(); ++i) {
      btVector3 d(dir(rng), dir(rng), dir(rng));
      if (d.length2() < 1e-6f) d = btVector3(0, 1, 0);
      velocity.push_back(d.normalized() * speed * (hi[i] - lo[i]).x());
    }
  }
  void add(btBroadphaseInterface& bp) {
    std::vector<btBroadphaseProxy*>& p = proxies.emplace_back();
    for (std::size_t i = 0; i < lo.size(); ++i)
      p.push_back(bp.createProxy(lo[i], hi[i], BOX_SHAPE_PROXYTYPE, reinterpret_cast<void*>(i + 1), 1, -1,
                                 &dispatcher));
    bp.calculateOverlappingPairs(&dispatcher);
  }
  void advance() {
    for (std::size_t i = 0; i < lo.size(); ++i) {
      for (int a = 0; a < 3; ++a)
        if (lo[i][a] + velocity[i][a] < 0 || hi[i][a] + velocity[i][a] > side) velocity[i][a] = -velocity[i][a];
      lo[i] += velocity[i], hi[i] += velocity[i];
    }
  }
  double update(btBroadphaseInterface& bp, std::size_t which) {
    return millisecondsOf([&] {
      for (std::size_t i = 0; i < lo.size(); ++i) bp.setAabb(proxies[which][i], lo[i], hi[i], &dispatcher);
      bp.calculateOverlappingPairs(&dispatcher);
    });
  }
  std::vector<btVector3> lo, hi, velocity;
  float side;
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher;
  std::vector<std::vector<btBroadphaseProxy*>> proxies;
};

void runMoving(const Options& o) {
  std::printf("%-8s %9s %6s %6s %12s %12s %12s %12s %9s\n", "scene", "N", "speed", "rays", "rays ms", "btDbvt ms",
              "frame ms", "btDbvt ms", "hits/ray");
  for (const std::string& sceneName : o.scenes)
    for (std::size_t n : o.sizes)
      for (float speed : o.speeds) {
        const QueryScene scene = makeScene(sceneName, n, 7);
        MovingWorld world(scene, speed, 3);
        gpucol::GridBroadphase grid;
        btDbvtBroadphase dbvt;
        world.add(grid), world.add(dbvt);
        std::vector<double> rayMs[2], frameMs[2];
        std::size_t hits[2] = {0, 0};
        btBroadphaseInterface* bps[2] = {&grid, &dbvt};
        for (int f = 0; f < o.movingFrames; ++f) {
          world.advance();
          QueryScene now = scene;
          now.lo = world.lo, now.hi = world.hi;
          const std::vector<Query> rays = makeQueries("short", now, o.queries, 100 + f);
          // Interleaved: each broad phase's frame, then the other's, on the same boxes and rays.
          for (int b = 0; b < 2; ++b) {
            const double update = world.update(*bps[b], std::size_t(b));
            rayMs[b].push_back(millisecondsOf([&] { hits[b] = runQueries(*bps[b], rays); }));
            frameMs[b].push_back(update + rayMs[b].back());
          }
        }
        std::printf("%-8s %9zu %6.2f %6d %12.3f %12.3f %12.3f %12.3f %9.1f%s\n", sceneName.c_str(), n, speed,
                    o.queries, median(rayMs[0]), median(rayMs[1]), median(frameMs[0]), median(frameMs[1]),
                    double(hits[0]) / o.queries, hits[0] == hits[1] ? "" : "  (btDbvt's fattened boxes)");
        const gpucol::GridBroadphaseQueryStats q = grid.queryStats();
        std::printf("  index builds %llu, indexed queries %llu, scans %llu\n",
                    (unsigned long long)q.indexBuilds, (unsigned long long)q.indexed, (unsigned long long)q.scans);
        std::fflush(stdout);
      }
}

void fill(btBroadphaseInterface& bp, const QueryScene& scene) {
  for (std::size_t i = 0; i < scene.lo.size(); ++i)
    bp.createProxy(scene.lo[i], scene.hi[i], BOX_SHAPE_PROXYTYPE, reinterpret_cast<void*>(i + 1), 1, -1,
                   nullptr);
}

void runAll(const Options& o) {
  std::printf("%-8s %9s %-6s %12s %12s %12s %9s %9s\n", "scene", "N", "query", "index us", "scan us",
              "btDbvt us", "scan/idx", "hits/q");
  for (const std::string& sceneName : o.scenes)
    for (std::size_t n : o.sizes) {
      const QueryScene scene = makeScene(sceneName, n, 7);
      gpucol::GridBroadphase indexed, scanned;
      GridBroadphaseOptions noIndex;
      noIndex.queryIndex = false;
      detail::GridBroadphaseAccess::setOptions(scanned, noIndex);
      btDbvtBroadphase dbvt;
      fill(indexed, scene), fill(scanned, scene), fill(dbvt, scene);
      btCollisionDispatcher* noDispatcher = nullptr;
      indexed.calculateOverlappingPairs(noDispatcher);
      scanned.calculateOverlappingPairs(noDispatcher);
      // Building the index against one scan: the 11th query after a change builds it (kScansBeforeIndex = 10).
      const std::vector<Query> warm = makeQueries("short", scene, 16, 99);
      std::vector<double> scanMs, buildMs;
      for (int r = 0; r < o.runs; ++r) {
        detail::GridBroadphaseAccess::setOptions(indexed, GridBroadphaseOptions{});  // drops the index
        for (int i = 0; i < 10; ++i) scanMs.push_back(millisecondsOf([&] { runQueries(indexed, {warm[i]}); }));
        buildMs.push_back(millisecondsOf([&] { runQueries(indexed, {warm[10]}); }));
      }
      const double scan = median(scanMs), build = median(buildMs);
      std::printf(
          "  index build (with its first query) %.3f ms, one scan %.3f ms: %.1f scans; index %.1f B/proxy\n",
          build, scan, build / scan, double(indexed.queryStats().indexBytes) / double(n));
      for (const char* kind : {"short", "long", "sweep", "box"}) {
        const std::vector<Query> queries = makeQueries(kind, scene, o.queries, 11);
        std::vector<double> ms[3];
        std::size_t hits[3] = {0, 0, 0};
        btBroadphaseInterface* bps[3] = {&indexed, &scanned, &dbvt};
        for (int r = 0; r < o.runs; ++r)
          for (int b = 0; b < 3; ++b)
            ms[b].push_back(millisecondsOf([&] { hits[b] = runQueries(*bps[b], queries); }));
        const double us[3] = {median(ms[0]) * 1e3 / o.queries, median(ms[1]) * 1e3 / o.queries,
                              median(ms[2]) * 1e3 / o.queries};
        std::printf("%-8s %9zu %-6s %12.2f %12.2f %12.2f %8.1fx %9.1f%s\n", sceneName.c_str(), n, kind, us[0],
                    us[1], us[2], us[1] / us[0], double(hits[0]) / o.queries,
                    hits[0] == hits[1] && hits[1] == hits[2] ? "" : "  (hits differ!)");
        std::fflush(stdout);
      }
    }
}

const CommandRegistration kRegistration([](CLI::App& app) {
  auto options = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "queries",
      "rayTest and aabbTest of gpucol::GridBroadphase through its query index and by scanning every proxy, "
      "beside btDbvtBroadphase on the same (unmoved) boxes: median microseconds per query; with --moving, "
      "rays in a world where every box moves, median ms per frame.");
  cmd->footer(
      "Example: gpucol-bench queries --n 10000,100000 --scenes uniform,mixed --queries 1000 --runs 5\n"
      "         gpucol-bench queries --n 10000 --scenes uniform --queries 500 --moving 60");
  cmd->add_option("--n", options->sizes, "proxy counts")->delimiter(',')->capture_default_str();
  cmd->add_option("--scenes", options->scenes, "uniform, mixed")->delimiter(',')->capture_default_str();
  cmd->add_option("--queries", options->queries, "queries of each kind per run")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--runs", options->runs, "timed runs (median reported)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--moving", options->movingFrames,
                  "frames of a world where every box moves (setAabb, calculateOverlappingPairs, then --queries "
                  "short rays), gpucol beside btDbvtBroadphase; 0: the static queries")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--speeds", options->speeds, "for --moving: box sizes each box moves per frame")
      ->delimiter(',')
      ->capture_default_str();
  cmd->callback([options] { options->movingFrames > 0 ? runMoving(*options) : runAll(*options); });
});

}  // namespace
}  // namespace gpucol::bench
