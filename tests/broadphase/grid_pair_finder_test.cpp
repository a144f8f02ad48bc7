// The CPU grid pair finder against the brute-force reference on the scenes of issue 4: uniform,
// clustered, mixed sizes with a few huge boxes, a plane, hundreds of identical boxes at one spot, far
// from the origin, negative coordinates, holes left by removed proxies; every option combination.
#include "broadphase/brute_force_pair_finder.h"
#include "broadphase/grid_pair_finder.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "broadphase/grid_choice.h"

namespace {

/// Owns the SoA arrays behind a ProxyArrays view.
struct Scene {
  std::vector<float> minX, minY, minZ, maxX, maxY, maxZ;
  std::vector<std::int32_t> group, mask;
  std::vector<std::uint8_t> flags;
  // The boxes as records (recordView), rewritten by each call.
  mutable std::vector<unsigned char> recordBytes;
  mutable std::vector<const unsigned char*> recordBlocks;

  void add(float cx, float cy, float cz, float hx, float hy, float hz,
           std::uint8_t flag = gpucol::kProxyActive, std::int32_t g = 1, std::int32_t m = -1) {
    minX.push_back(cx - hx), minY.push_back(cy - hy), minZ.push_back(cz - hz);
    maxX.push_back(cx + hx), maxY.push_back(cy + hy), maxZ.push_back(cz + hz);
    group.push_back(g), mask.push_back(m), flags.push_back(flag);
  }
  gpucol::ProxyArrays view() const {
    gpucol::ProxyArrays v;
    v.count = std::uint32_t(flags.size());
    v.minX = minX.data(), v.minY = minY.data(), v.minZ = minZ.data();
    v.maxX = maxX.data(), v.maxY = maxY.data(), v.maxZ = maxZ.data();
    v.group = group.data(), v.mask = mask.data(), v.flags = flags.data();
    return v;
  }
  /// The same scene with its boxes in records (ProxyArrays::records, as GridBroadphase hands its proxies to
  /// the CPU finder): blocks of 8 records of 40 bytes, stored in reverse block order, the corners at bytes 8
  /// and 24 and NaN in every other byte, so that a wrong block, stride or offset changes the pairs.
  gpucol::ProxyArrays recordView() const {
    constexpr std::uint32_t kBits = 3, kStride = 40, kMinAt = 8, kMaxAt = 24;
    const std::size_t n = flags.size(), blocks = (n >> kBits) + 1, blockBytes = std::size_t(kStride) << kBits;
    recordBytes.assign(blocks * blockBytes, 0xFF);
    recordBlocks.resize(blocks);
    for (std::size_t b = 0; b < blocks; ++b)
      recordBlocks[b] = recordBytes.data() + (blocks - 1 - b) * blockBytes;
    for (std::size_t i = 0; i < n; ++i) {
      unsigned char* r =
          recordBytes.data() + (blocks - 1 - (i >> kBits)) * blockBytes + (i & ((1u << kBits) - 1)) * kStride;
      const float lo[3] = {minX[i], minY[i], minZ[i]}, hi[3] = {maxX[i], maxY[i], maxZ[i]};
      std::memcpy(r + kMinAt, lo, sizeof lo);
      std::memcpy(r + kMaxAt, hi, sizeof hi);
    }
    gpucol::ProxyArrays v = view();
    v.minX = v.minY = v.minZ = v.maxX = v.maxY = v.maxZ = nullptr;
    v.records = gpucol::BoxRecords{recordBlocks.data(), kBits, kStride, kMinAt, kMaxAt};
    return v;
  }
};

Scene uniformCloud(int n, float side, float halfSize, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-side, side), size(0.2f * halfSize, halfSize);
  Scene s;
  for (int i = 0; i < n; ++i) s.add(pos(rng), pos(rng), pos(rng), size(rng), size(rng), size(rng));
  return s;
}

/// Checks the finder against brute force with every combination of options, grid forced and not, the grid
/// searched whole and in slabs (of 64 boxes, so that small scenes have many; by home cell where the boxes
/// are of about one size), the boxes in arrays and in records.
void expectMatchesBruteForce(const Scene& scene, const std::string& what, std::uint64_t minPairs = 1,
                             std::uint32_t hugeCellLimit = gpucol::PairFinderOptions{}.hugeCellLimit) {
  std::vector<std::uint64_t> reference;
  gpucol::BruteForcePairFinder().findPairs(scene.view(), gpucol::PairFinderOptions{}, reference);
  ASSERT_GE(reference.size(), minPairs) << what << ": the scene should have overlaps to test";
  auto finder = gpucol::makeCpuPairFinder();
  for (bool records : {false, true})
    for (std::uint32_t below : {0u, 1000000u})
      for (auto rule : {gpucol::CellSizeRule::Size, gpucol::CellSizeRule::Density})
        for (auto output : {gpucol::PairOutput::Compacted, gpucol::PairOutput::BitMask})
          for (auto sqrtMode : {gpucol::MappingSqrt::Double, gpucol::MappingSqrt::Newton})
            for (auto tiling : {gpucol::SlabTiling::Off, gpucol::SlabTiling::Always}) {
              gpucol::PairFinderOptions o;
              o.bruteForceBelow = below;
              o.cellSizeRule = rule;
              o.output = output;
              o.mappingSqrt = sqrtMode;
              o.slabTiling = tiling;
              o.slabBoxes = 64;
              // Slabs do not use the mapping function: its two modes take the two ways of reading boxes.
              o.slabBoxReading = sqrtMode == gpucol::MappingSqrt::Newton ? gpucol::SlabBoxReading::InPlace
                                                                         : gpucol::SlabBoxReading::Copy;
              o.hugeCellLimit = hugeCellLimit;
              std::vector<std::uint64_t> pairs;
              finder->findPairs(records ? scene.recordView() : scene.view(), o, pairs);
              ASSERT_EQ(pairs, reference)
                  << what << " records=" << records << " below=" << below << " rule=" << int(rule)
                  << " output=" << int(output) << " sqrt=" << int(sqrtMode) << " tiling=" << int(tiling)
                  << " grid=" << finder->stats().usedGrid
                  << " slabs=" << finder->stats().slabs << " byHomeCell=" << finder->stats().homeCells;
              const gpucol::PairFinderStats& st = finder->stats();
              EXPECT_EQ(st.usedGrid, below == 0) << what;
              if (rule == gpucol::CellSizeRule::Density) {
                EXPECT_FALSE(st.homeCells) << what;
              }
              if (tiling == gpucol::SlabTiling::Off || output == gpucol::PairOutput::BitMask) {
                EXPECT_EQ(st.slabs, 0u) << what;
                EXPECT_FALSE(st.homeCells) << what;
              } else if (st.slabs > 0) {
                // By home cell, the boxes are always copied (into cell order).
                EXPECT_EQ(st.slabBoxesInPlace,
                          !st.homeCells && o.slabBoxReading == gpucol::SlabBoxReading::InPlace)
                    << what;
              }
              if (!st.homeCells) {
                EXPECT_EQ(st.wideBoxes, 0u) << what;
              }
            }
}

TEST(GridPairFinder, UniformCloud) {
  expectMatchesBruteForce(uniformCloud(4000, 20.0f, 0.8f, 1), "uniform");
}

TEST(GridPairFinder, Clustered) {
  std::mt19937 rng(2);
  std::normal_distribution<float> around(0.0f, 1.5f);
  std::uniform_real_distribution<float> centre(-200.0f, 200.0f), size(0.1f, 0.6f);
  Scene s;
  for (int c = 0; c < 8; ++c) {
    const float cx = centre(rng), cy = centre(rng), cz = centre(rng);
    for (int i = 0; i < 400; ++i)
      s.add(cx + around(rng), cy + around(rng), cz + around(rng), size(rng), size(rng), size(rng));
  }
  expectMatchesBruteForce(s, "clustered");
}

TEST(GridPairFinder, MixedSizesWithHugeBoxes) {
  Scene s = uniformCloud(3000, 30.0f, 0.5f, 3);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> pos(-30.0f, 30.0f), big(2.0f, 6.0f);
  for (int i = 0; i < 200; ++i) s.add(pos(rng), pos(rng), pos(rng), big(rng), big(rng), big(rng));
  s.add(0, -31, 0, 100, 1, 100);  // a ground slab larger than the scene
  s.add(5, 0, 0, 2, 60, 2);       // a pillar through it
  s.add(0, 0, 0, 40, 40, 40);     // a box holding everything
  expectMatchesBruteForce(s, "mixed + huge");
  auto finder = gpucol::makeCpuPairFinder();
  std::vector<std::uint64_t> pairs;
  gpucol::PairFinderOptions o;
  o.bruteForceBelow = 0;
  finder->findPairs(s.view(), o, pairs);
  EXPECT_GE(finder->stats().hugeProxies, 3u)
      << "the slab, pillar and the enclosing box are kept out of the grid";
}

TEST(GridPairFinder, HugeBoxesTestedThroughTheirCells) {
  // Huge boxes covering a few hundred cells among 20,000 binned ones take the cell path of stage 3, where
  // cells inside a huge box's range report their home entries without a test; boxes touching the huge
  // boxes' faces (touching counts) and crossing their boundary cells check the tested part.
  Scene s = uniformCloud(20000, 25.0f, 0.6f, 9);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> pos(-20.0f, 20.0f), big(3.5f, 6.0f);
  for (int i = 0; i < 30; ++i) {
    const float cx = pos(rng), cy = pos(rng), cz = pos(rng), hx = big(rng), hy = big(rng), hz = big(rng);
    s.add(cx, cy, cz, hx, hy, hz);
    s.add(cx - hx - 0.25f, cy, cz, 0.25f, 0.25f, 0.25f);  // touches the min x face
    s.add(cx, cy + hy + 0.5f, cz, 0.5f, 0.5f, 0.5f);      // touches the max y face
    s.add(cx, cy, cz - hz, 0.3f, 0.3f, 0.3f);             // straddles the min z face
  }
  const gpucol::ProxyArrays view = s.view();
  const std::vector<std::uint64_t> reference = gpucol::BruteForcePairFinder::pairsOf(view);
  auto finder = gpucol::makeCpuPairFinder();
  gpucol::PairFinderOptions o;
  o.bruteForceBelow = 0;
  std::vector<std::uint64_t> pairs;
  finder->findPairs(view, o, pairs);
  EXPECT_EQ(pairs, reference);
  EXPECT_EQ(finder->stats().hugeProxies, 30u);
  // Through the cells, a huge box visits far fewer entries than the 20,090 binned boxes it would test
  // one by one.
  EXPECT_LT(finder->stats().candidates, 30u * 20090u / 2);
}

TEST(GridPairFinder, BoxesSpanningMoreThan255CellsOnAnAxis) {
  // With no huge limit, rods across a thin square of small boxes are binned across about 290 cells on x or
  // on z, more than a packed cell range holds (8 bits per axis): their cells are walked from the whole range
  // instead, in the whole grid and in the slabs, which cut one of the two axes (so the rods along the other
  // one stay wide in every slab). The square is dense enough for a counting sort and slabs (cells <= 8 ×
  // boxes + 1024).
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> xz(-50.0f, 50.0f), y(-0.04f, 0.04f), size(0.07f, 0.09f);
  Scene s;
  for (int i = 0; i < 12000; ++i) s.add(xz(rng), y(rng), xz(rng), size(rng), 0.05f, size(rng));
  for (int i = 0; i < 4; ++i) {
    s.add(0.01f * xz(rng), y(rng), xz(rng), 49.5f, 0.05f, 0.05f);
    s.add(xz(rng), y(rng), 0.01f * xz(rng), 0.05f, 0.05f, 49.5f);
  }
  const std::vector<std::uint64_t> reference = gpucol::BruteForcePairFinder::pairsOf(s.view());
  ASSERT_GE(reference.size(), 100u);
  auto finder = gpucol::makeCpuPairFinder();
  for (bool records : {false, true})
    for (auto tiling : {gpucol::SlabTiling::Off, gpucol::SlabTiling::Always}) {
      gpucol::PairFinderOptions o;
      o.bruteForceBelow = 0;
      o.hugeCellLimit = std::numeric_limits<std::uint32_t>::max();
      o.slabTiling = tiling;
      std::vector<std::uint64_t> pairs;
      finder->findPairs(records ? s.recordView() : s.view(), o, pairs);
      ASSERT_EQ(pairs, reference) << "records=" << records << " tiling=" << int(tiling);
      const gpucol::PairFinderStats& st = finder->stats();
      EXPECT_EQ(st.hugeProxies, 0u);
      EXPECT_GT(std::min(st.dims[0], st.dims[2]), 270u) << "the rods must span more than 255 cells";
      EXPECT_EQ(st.slabs > 0, tiling == gpucol::SlabTiling::Always)
          << st.dims[0] << " x " << st.dims[1] << " x " << st.dims[2] << " cells: not dense?";
    }
}

TEST(GridPairFinder, SlabsAcrossMoreThan65536Layers) {
  // A line of box pairs about 70,000 cells long: the slab planning keeps each box's layers in 16 bits each
  // only below 65,536 layers, so here it reads them from the boxes in all its passes.
  std::mt19937 rng(22);
  std::uniform_real_distribution<float> jitter(-0.02f, 0.02f);
  Scene s;
  for (int i = 0; i < 4500; ++i) {
    const float x = 3.1f * float(i);
    s.add(x, 0, 0, 0.05f, 0.05f, 0.05f);
    s.add(x + 0.08f + jitter(rng), jitter(rng), 0, 0.05f, 0.05f, 0.05f);  // overlaps the first but for a few
  }
  const std::vector<std::uint64_t> reference = gpucol::BruteForcePairFinder::pairsOf(s.view());
  ASSERT_GE(reference.size(), 1000u);
  auto finder = gpucol::makeCpuPairFinder();
  for (bool records : {false, true}) {
    gpucol::PairFinderOptions o;
    o.bruteForceBelow = 0;
    o.slabTiling = gpucol::SlabTiling::Always;
    std::vector<std::uint64_t> pairs;
    finder->findPairs(records ? s.recordView() : s.view(), o, pairs);
    ASSERT_EQ(pairs, reference) << "records=" << records;
    EXPECT_GT(finder->stats().dims[0], 65536u);
    EXPECT_GE(finder->stats().slabs, 8u);
    EXPECT_EQ(finder->stats().slabAxisKept, records) << "in records, every pass reads the kept extents";
  }
}

/// Boxes in records: the grid choice keeps their extents along the last plan's slab axis, and the plan takes
/// them when its axis is the same, else reads the boxes. The scene's longest axis turns from z to x. Huge
/// boxes among the first of more than 16,384 boxes make the grid choice close up its chunks' binned stretches
/// (and the kept extents with them).
TEST(GridPairFinder, SlabPlanTakesTheExtentsKeptAlongItsAxis) {
  const Scene alongZ = [] {
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> across(-8.0f, 8.0f), along(-80.0f, 80.0f), size(0.1f, 0.6f);
    Scene s;
    for (int i = 0; i < 17000; ++i) {
      const float huge = i % 1000 == 7 && i < 16384 ? 40.0f : 0.0f;
      s.add(across(rng), across(rng), along(rng), size(rng), size(rng), size(rng) + huge);
    }
    return s;
  }();
  Scene alongX = alongZ;
  std::swap(alongX.minX, alongX.minZ);
  std::swap(alongX.maxX, alongX.maxZ);
  auto finder = gpucol::makeCpuPairFinder();  // its first guess: x
  gpucol::PairFinderOptions o;
  o.bruteForceBelow = 0;
  o.slabTiling = gpucol::SlabTiling::Always;
  const std::vector<std::uint64_t> pairsAlongZ = gpucol::BruteForcePairFinder::pairsOf(alongZ.view()),
                                   pairsAlongX = gpucol::BruteForcePairFinder::pairsOf(alongX.view());
  struct Step {
    const Scene* scene;
    const std::vector<std::uint64_t>* reference;
    bool records;
    bool kept;
  };
  const Step steps[] = {{&alongZ, &pairsAlongZ, true, false},  {&alongZ, &pairsAlongZ, true, true},
                        {&alongZ, &pairsAlongZ, false, false}, {&alongX, &pairsAlongX, true, false},
                        {&alongX, &pairsAlongX, true, true},   {&alongZ, &pairsAlongZ, true, false}};
  int k = 0;
  for (const Step& step : steps) {
    std::vector<std::uint64_t> pairs;
    finder->findPairs(step.records ? step.scene->recordView() : step.scene->view(), o, pairs);
    ASSERT_EQ(pairs, *step.reference) << "step " << k;
    EXPECT_GE(finder->stats().slabs, 8u) << "step " << k;
    EXPECT_GE(finder->stats().hugeProxies, 10u) << "step " << k;
    EXPECT_EQ(finder->stats().slabAxisKept, step.kept) << "step " << k;
    ++k;
  }
}

/// The survey a caller's own pass over `s` makes at cell edge `cell` (BoxSurvey), with each slot's extent
/// along `axis`.
gpucol::BoxSurvey surveyOf(const Scene& s, float cell, std::uint32_t hugeCellLimit, int axis) {
  gpucol::BoxSurvey survey;
  survey.cell = cell;
  survey.hugeCellLimit = hugeCellLimit;
  survey.extents.axis = axis;
  survey.extents.bySlot = true;
  for (int a = 0; a < 3; ++a)
    survey.lo[a] = std::numeric_limits<float>::infinity(), survey.hi[a] = -survey.lo[a];
  const gpucol::ProxyArrays v = s.view();
  for (std::uint32_t i = 0; i < v.count; ++i) {
    const gpucol::BoxCorners b = v.box(i);
    survey.extents.lo.push_back(gpucol::floatBits(b.lo[axis]));
    survey.extents.hi.push_back(gpucol::floatBits(b.hi[axis]));
    if (!(v.flags[i] & gpucol::kProxyActive)) continue;
    if (gpucol::isHuge(b, cell, hugeCellLimit)) {
      survey.huge.push_back(i);
      continue;
    }
    for (int a = 0; a < 3; ++a)
      survey.lo[a] = std::min(survey.lo[a], b.lo[a]), survey.hi[a] = std::max(survey.hi[a], b.hi[a]);
  }
  return survey;
}

/// A survey of the boxes made by the caller (GridBroadphase's scan, in place) replaces the grid choice's
/// walk: the huge list, the bounds and the slab axis's extents by slot come from it. It is taken only at
/// about this search's cell edge; its huge list and bounds never change the pairs; its extents are taken
/// only along the plan's axis. Holes (inactive slots) and huge boxes make slot and binned index differ.
TEST(GridPairFinder, GridChoiceTakesTheCallersSurvey) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<float> across(-8.0f, 8.0f), along(-80.0f, 80.0f), size(0.1f, 0.6f);
  Scene s;
  for (int i = 0; i < 17000; ++i) {
    const float huge = i % 1000 == 7 ? 40.0f : 0.0f;
    s.add(across(rng), across(rng), along(rng), size(rng), size(rng), size(rng) + huge,
          i % 97 == 3 ? std::uint8_t(0) : gpucol::kProxyActive);
  }
  const std::vector<std::uint64_t> reference = gpucol::BruteForcePairFinder::pairsOf(s.view());
  ASSERT_GE(reference.size(), 1000u);
  auto finder = gpucol::makeCpuPairFinder();
  gpucol::PairFinderOptions o;
  o.bruteForceBelow = 0;
  o.slabTiling = gpucol::SlabTiling::Always;
  float cell = 0.0f;
  int axis = -1;
  EXPECT_FALSE(finder->surveyWanted(o, cell, axis)) << "no search yet";
  std::vector<std::uint64_t> pairs;
  finder->findPairs(s.recordView(), o, pairs);
  ASSERT_EQ(pairs, reference);
  EXPECT_FALSE(finder->surveyWanted(o, cell, axis)) << "a first search keeps its grid for few moves";
  // Every box moved: a full search, which keeps no grid.
  const std::vector<std::uint8_t> moved(s.flags.size(), 1);
  gpucol::ProxyArrays allMoved = s.recordView();
  allMoved.moved = moved.data();
  finder->findPairs(allMoved, o, pairs);
  ASSERT_EQ(pairs, reference);
  const std::uint32_t hugeWalked = finder->stats().hugeProxies;
  EXPECT_GE(hugeWalked, 10u);
  ASSERT_TRUE(finder->surveyWanted(o, cell, axis));
  EXPECT_EQ(axis, 2) << "the scene is longest along z";
  struct Case {
    const char* what;
    float cellFactor;
    int axis;
    bool clearHuge;
    bool taken;
    bool extentsTaken;  // the survey's
  };
  const Case cases[] = {{"as asked", 1.0f, 2, false, true, true},
                        {"cell a little off", 1.5f, 2, false, true, true},
                        {"another axis", 1.0f, 0, false, true, false},
                        {"no huge listed", 1.0f, 2, true, true, true},
                        {"cell far off", 4.0f, 2, false, false, false}};
  for (const Case& c : cases) {
    gpucol::BoxSurvey survey = surveyOf(s, cell * c.cellFactor, o.hugeCellLimit, c.axis);
    if (c.clearHuge) survey.huge.clear();
    gpucol::ProxyArrays v = allMoved;
    v.survey = &survey;
    finder->findPairs(v, o, pairs);
    ASSERT_EQ(pairs, reference) << c.what;
    const gpucol::PairFinderStats& st = finder->stats();
    EXPECT_EQ(st.surveyTaken, c.taken) << c.what;
    // Not taken, the grid choice reads the boxes and keeps their extents itself.
    EXPECT_EQ(st.slabAxisKept, c.extentsTaken || !c.taken) << c.what;
    EXPECT_EQ(survey.extents.lo.empty(), c.extentsTaken) << c.what << ": the extents taken over";
    EXPECT_GE(st.slabs, 8u) << c.what;
    EXPECT_EQ(st.hugeProxies, c.clearHuge ? 0u
                              : c.taken   ? std::uint32_t(survey.huge.size())
                                          : hugeWalked)
        << c.what;
  }
}

TEST(GridPairFinder, AllInOnePlane) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> pos(-40.0f, 40.0f), size(0.2f, 1.0f);
  Scene s;
  for (int i = 0; i < 3000; ++i)
    s.add(pos(rng), 0.0f, pos(rng), size(rng), 0.0f, size(rng));  // zero thickness
  expectMatchesBruteForce(s, "plane");
}

TEST(GridPairFinder, HundredsOfIdenticalBoxesAtOneSpot) {
  Scene s = uniformCloud(1500, 25.0f, 0.5f, 5);
  for (int i = 0; i < 600; ++i) s.add(1.0f, 2.0f, 3.0f, 0.5f, 0.5f, 0.5f);
  expectMatchesBruteForce(s, "identical", 600 * 599 / 2);
}

TEST(GridPairFinder, FarFromTheOriginAndNegative) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<float> pos(-30.0f, 30.0f), size(0.3f, 1.0f);
  Scene far, negative;
  for (int i = 0; i < 3000; ++i) {
    far.add(1e6f + pos(rng), 1e6f + pos(rng), -1e6f + pos(rng), size(rng), size(rng), size(rng));
    negative.add(-500.0f + pos(rng), -500.0f + pos(rng), -500.0f + pos(rng), size(rng), size(rng), size(rng));
  }
  expectMatchesBruteForce(far, "far 1e6");
  expectMatchesBruteForce(negative, "negative");
}

TEST(GridPairFinder, TouchingBoxesCount) {
  // A lattice of unit cubes that touch face to face exactly: every neighbour pair must be reported.
  Scene s;
  for (int x = 0; x < 12; ++x)
    for (int y = 0; y < 12; ++y)
      for (int z = 0; z < 12; ++z) s.add(float(x), float(y), float(z), 0.5f, 0.5f, 0.5f);
  // 26-neighbourhood: touching faces, edges and corners.
  expectMatchesBruteForce(s, "touching lattice", 3 * 11 * 144);
}

TEST(GridPairFinder, FiltersStaticAndHoles) {
  Scene s = uniformCloud(3000, 15.0f, 0.8f, 7);
  std::mt19937 rng(7);
  for (std::size_t i = 0; i < s.flags.size(); ++i) {
    const unsigned r = rng() % 10;
    if (r == 0) s.flags[i] = 0;  // removed proxy: a hole
    if (r == 1) s.flags[i] = gpucol::kProxyActive | gpucol::kProxyStatic;
    s.group[i] = std::int32_t(1u << (rng() % 4));
    s.mask[i] = std::int32_t(rng() % 16);
  }
  expectMatchesBruteForce(s, "filters + static + holes");
}

TEST(GridPairFinder, AddAndRemoveBetweenSearches) {
  // One finder reused over steps while proxies come, go and move (scratch reuse must not leak state).
  Scene s = uniformCloud(2500, 15.0f, 0.7f, 8);
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> step(-0.3f, 0.3f);
  auto finder = gpucol::makeCpuPairFinder();
  gpucol::PairFinderOptions o;
  o.bruteForceBelow = 0;
  for (int t = 0; t < 6; ++t) {
    for (std::size_t i = 0; i < s.flags.size(); ++i) {
      if (rng() % 20 == 0) s.flags[i] ^= gpucol::kProxyActive;
      const float dx = step(rng), dy = step(rng), dz = step(rng);
      s.minX[i] += dx, s.maxX[i] += dx, s.minY[i] += dy, s.maxY[i] += dy, s.minZ[i] += dz, s.maxZ[i] += dz;
    }
    for (int i = 0; i < 50; ++i) s.add(step(rng) * 40, step(rng) * 40, step(rng) * 40, 0.5f, 0.5f, 0.5f);
    std::vector<std::uint64_t> pairs;
    finder->findPairs(s.view(), o, pairs);
    ASSERT_EQ(pairs, gpucol::BruteForcePairFinder::pairsOf(s.view())) << "step " << t;
  }
}

/// Stage 11: with ProxyArrays::moved, a finder keeps its grid while few proxies change. Each step a few
/// boxes move (some far, some out of the grid's bounds), vanish, reappear, change filters, and a huge
/// box moves; the pairs must equal brute force and the unchanged proxies must be counted as resting.
/// With `callerKeepsPairs`, the caller hands the finder its previous result (ProxyArrays::lastPairs), as
/// GridBroadphase does (with the boxes in records, as it does too), except at one step, which must then be a
/// full search. `tiling`: Auto cuts the full searches into slabs and bins the kept grid after them; Off keeps
/// the whole-grid search's own cells and entries.
void restingScenario(bool callerKeepsPairs, gpucol::SlabTiling tiling) {
  Scene s = uniformCloud(6000, 20.0f, 0.7f, 12);
  for (std::size_t i = 0; i < s.flags.size(); i += 5) s.flags[i] |= gpucol::kProxyStatic;
  s.add(0, -20.5f, 0, 25.0f, 0.5f, 25.0f, gpucol::kProxyActive | gpucol::kProxyStatic);  // huge static ground
  s.add(0, 0, 0, 3.0f, 20.0f, 3.0f);                                                     // huge moving pillar
  const std::uint32_t pillar = std::uint32_t(s.flags.size() - 1);
  std::vector<std::uint8_t> moved(s.flags.size(), 1);
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> step(-0.3f, 0.3f), far(-30.0f, 30.0f);
  auto finder = gpucol::makeCpuPairFinder();
  gpucol::PairFinderOptions o;
  o.bruteForceBelow = 0;
  o.slabTiling = tiling;
  int incrementalSteps = 0;
  constexpr int kWithoutLastPairs = 9;  // with callerKeepsPairs: the step that does not hand them over
  gpucol::PackedPairs last;
  for (int t = 0; t < 12; ++t) {
    gpucol::ProxyArrays view = callerKeepsPairs ? s.recordView() : s.view();
    view.moved = moved.data();
    if (callerKeepsPairs && t != kWithoutLastPairs) view.lastPairs = &last;
    std::vector<std::uint64_t> pairs;
    finder->findPairs(view, o, pairs);
    ASSERT_EQ(pairs, gpucol::BruteForcePairFinder::pairsOf(s.view())) << "step " << t;
    if (callerKeepsPairs && t == kWithoutLastPairs) {
      EXPECT_FALSE(finder->stats().incremental) << "the finder kept no pairs of its own to carry over";
    }
    last.assign(pairs);
    std::uint32_t active = 0, changedActive = 0;
    for (std::size_t i = 0; i < s.flags.size(); ++i) {
      active += (s.flags[i] & gpucol::kProxyActive) != 0;
      changedActive += (s.flags[i] & gpucol::kProxyActive) && moved[i];
    }
    const gpucol::PairFinderStats& st = finder->stats();
    EXPECT_EQ(st.restingProxies + st.rebinnedProxies, active) << "step " << t;
    if (t == 0) {
      EXPECT_FALSE(st.incremental) << "the first search has no grid to keep";
      EXPECT_EQ(st.slabs > 0, tiling == gpucol::SlabTiling::Auto);
    }
    if (st.incremental) {
      ++incrementalSteps;
      // Since the grid was built, only the slots changed in the steps after it are re-binned.
      EXPECT_GE(st.rebinnedProxies, changedActive) << "step " << t;
      EXPECT_GE(st.restingProxies, active * 3 / 4) << "step " << t;
    } else {
      EXPECT_EQ(st.restingProxies, 0u);
    }
    std::fill(moved.begin(), moved.end(), std::uint8_t(0));
    if (t == 6) {
      // Many moves at once: the finder must fall back to a full search (and build a new grid).
      for (std::size_t i = 0; i < s.flags.size(); i += 2) {
        const float d = step(rng);
        s.minX[i] += d, s.maxX[i] += d;
        moved[i] = 1;
      }
      continue;
    }
    for (int k = 0; k < 60; ++k) {
      const std::size_t i = rng() % s.flags.size();
      moved[i] = 1;
      switch (k % 6) {
        case 0:
          s.flags[i] ^= gpucol::kProxyActive;
          break;  // vanish or come back
        case 1:
          s.group[i] = (s.group[i] == 1 ? 2 : 1), s.mask[i] = 1;
          break;   // filter change
        case 2: {  // jump far, even out of the grid
          const float c[3] = {far(rng), far(rng), far(rng)};
          const float h = 0.5f * (s.maxX[i] - s.minX[i]);
          s.minX[i] = c[0] - h, s.maxX[i] = c[0] + h, s.minY[i] = c[1] - h, s.maxY[i] = c[1] + h;
          s.minZ[i] = c[2] - h, s.maxZ[i] = c[2] + h;
          break;
        }
        default: {
          const float dx = step(rng), dy = step(rng), dz = step(rng);
          s.minX[i] += dx, s.maxX[i] += dx, s.minY[i] += dy, s.maxY[i] += dy, s.minZ[i] += dz,
              s.maxZ[i] += dz;
        }
      }
    }
    if (t % 3 == 1) {
      s.minX[pillar] += 1.5f, s.maxX[pillar] += 1.5f;
      moved[pillar] = 1;
    }
    for (int k = 0; k < 10; ++k) {  // new proxies
      s.add(far(rng) * 0.6f, far(rng) * 0.6f, far(rng) * 0.6f, 0.5f, 0.5f, 0.5f);
      moved.push_back(1);
    }
  }
  EXPECT_GE(incrementalSteps, callerKeepsPairs ? 7 : 8) << "the kept grid was not used";
}

TEST(GridPairFinder, RestingProxiesAreNotRebinnedAndPairsStayExact) {
  for (auto tiling : {gpucol::SlabTiling::Auto, gpucol::SlabTiling::Off}) {
    SCOPED_TRACE(tiling == gpucol::SlabTiling::Auto ? "slabs" : "whole grid");
    restingScenario(false, tiling);
  }
}

TEST(GridPairFinder, RestingPairsCarriedOverFromTheCallersCopy) {
  for (auto tiling : {gpucol::SlabTiling::Auto, gpucol::SlabTiling::Off}) {
    SCOPED_TRACE(tiling == gpucol::SlabTiling::Auto ? "slabs" : "whole grid");
    restingScenario(true, tiling);
  }
}

TEST(GridPairFinder, SparseGridPath) {
  // Two far-apart clusters make a grid with many more cells than keys: the explicit-key sort path.
  Scene s = uniformCloud(1500, 5.0f, 0.5f, 9);
  Scene t = uniformCloud(1500, 5.0f, 0.5f, 10);
  for (std::size_t i = 0; i < t.flags.size(); ++i)
    s.add(0.5f * (t.minX[i] + t.maxX[i]) + 5000.0f, 0.5f * (t.minY[i] + t.maxY[i]) + 5000.0f,
          0.5f * (t.minZ[i] + t.maxZ[i]) + 5000.0f, 0.5f * (t.maxX[i] - t.minX[i]),
          0.5f * (t.maxY[i] - t.minY[i]), 0.5f * (t.maxZ[i] - t.minZ[i]));
  expectMatchesBruteForce(s, "sparse");
}

/// Stage 11 finds a moved box's pairs with unchanged boxes through the kept grid's entries alone, so every
/// binned box must be listed, under its own name, in every cell it overlaps. Each round a fresh finder keeps
/// the grid of its first search and then one tenth of the boxes are marked moved (without moving, so brute
/// force stays the reference); over ten rounds every box is looked up from the other nine tenths, through
/// the grid binned after the slabs and through the whole-grid search's own.
TEST(GridPairFinder, KeptGridListsEveryBoxInEveryCellItOverlaps) {
  Scene s = uniformCloud(5000, 16.0f, 0.9f, 41);
  s.add(0, 0, 0, 4, 4, 4);  // a huge box (kept aside, tested one by one)
  const std::vector<std::uint64_t> reference = gpucol::BruteForcePairFinder::pairsOf(s.view());
  ASSERT_GE(reference.size(), 3000u);
  for (auto tiling : {gpucol::SlabTiling::Auto, gpucol::SlabTiling::Off}) {
    gpucol::PairFinderOptions o;
    o.bruteForceBelow = 0;
    o.slabTiling = tiling;
    for (std::size_t round = 0; round < 10; ++round) {
      SCOPED_TRACE(std::string(tiling == gpucol::SlabTiling::Auto ? "slabs" : "whole grid") + ", round " +
                   std::to_string(round));
      auto finder = gpucol::makeCpuPairFinder();
      gpucol::ProxyArrays view = s.view();
      std::vector<std::uint64_t> pairs;
      finder->findPairs(view, o, pairs);
      EXPECT_EQ(finder->stats().slabs > 0, tiling == gpucol::SlabTiling::Auto);
      std::vector<std::uint8_t> moved(s.flags.size(), 0);
      for (std::size_t i = round; i < moved.size(); i += 10) moved[i] = 1;
      view.moved = moved.data();
      finder->findPairs(view, o, pairs);
      ASSERT_TRUE(finder->stats().incremental);
      ASSERT_EQ(pairs, reference);
    }
  }
}

/// SlabTiling::Auto cuts full searches into slabs, with the same pairs and the same (cell, box) entries as
/// the whole grid (Off), and bins the grid of a first search, or of one where few proxies moved, after the
/// slabs for stage 11, whose next search then uses it. Huge boxes cross many slabs, some through their
/// cells, some one by one.
TEST(GridPairFinder, SlabSearchAndTheGridKeptAfterIt) {
  Scene s = uniformCloud(12000, 22.0f, 0.6f, 13);
  s.add(0, -23, 0, 30, 1, 30);  // a ground box crossing every slab: tested one by one
  s.add(0, 0, 0, 5, 5, 5);      // a box of a few hundred cells: tested through its cells
  s.add(10, 5, -8, 1, 25, 1);   // a pillar along the slab axis
  std::vector<std::uint8_t> moved(s.flags.size(), 1);
  auto finder = gpucol::makeCpuPairFinder();
  gpucol::PairFinderOptions o, whole;
  o.bruteForceBelow = whole.bruteForceBelow = 0;
  whole.slabTiling = gpucol::SlabTiling::Off;
  std::vector<std::uint64_t> pairs;
  gpucol::ProxyArrays view = s.view();
  auto wholeFinder = gpucol::makeCpuPairFinder();
  wholeFinder->findPairs(view, whole, pairs);
  EXPECT_EQ(wholeFinder->stats().slabs, 0u);
  auto search = [&](const char* what) {
    SCOPED_TRACE(what);
    finder->findPairs(view, o, pairs);
    ASSERT_EQ(pairs, gpucol::BruteForcePairFinder::pairsOf(view));
  };
  search("first");
  EXPECT_GE(finder->stats().slabs, 8u);
  EXPECT_GE(finder->stats().hugeProxies, 3u);
  EXPECT_EQ(finder->stats().keys, wholeFinder->stats().keys) << "each (cell, box) entry lies in one slab";
  EXPECT_FALSE(finder->stats().incremental);
  // A step where few proxies move. The first search kept its grid: only the moved are binned.
  view.moved = moved.data();
  std::fill(moved.begin(), moved.end(), std::uint8_t(0));
  auto moveFew = [&](std::size_t first) {
    for (std::size_t i = first; i < moved.size(); i += 50) {
      s.minY[i] += 0.2f, s.maxY[i] += 0.2f;
      moved[i] = 1;
    }
  };
  moveFew(0);
  search("few moved after the first");
  EXPECT_TRUE(finder->stats().incremental);
  EXPECT_EQ(finder->stats().slabs, 0u);
  // Most move: a slab search that keeps nothing.
  std::fill(moved.begin(), moved.end(), std::uint8_t(1));
  search("all moved");
  EXPECT_GE(finder->stats().slabs, 8u);
  EXPECT_FALSE(finder->stats().incremental);
  // Few moved since: a slab search whose grid is kept, then the kept grid serves.
  std::fill(moved.begin(), moved.end(), std::uint8_t(0));
  moveFew(7);
  search("few moved after all moved");
  EXPECT_GE(finder->stats().slabs, 8u);
  EXPECT_FALSE(finder->stats().incremental);
  std::fill(moved.begin(), moved.end(), std::uint8_t(0));
  moveFew(13);
  search("few moved again");
  EXPECT_TRUE(finder->stats().incremental);
}

/// A cloud of unit boxes (one per 8 unit volumes), with every 7th box on a lattice of touching unit cubes, and
/// `wide` boxes of half extent 0.95 at odd indices (never in stage 2's sample of every 2nd box, so larger than
/// the home cells).
Scene unitBoxCloud(int n, float offset, int wide, std::uint32_t seed) {
  std::mt19937 rng(seed);
  const float side = std::cbrt(8.0f * float(n));
  std::uniform_real_distribution<float> pos(0.0f, side);
  std::uniform_int_distribution<int> lattice(0, int(side) - 1);
  Scene s;
  for (int i = 0; i < n; ++i) {
    const bool onLattice = i % 7 == 0;
    float c[3];
    for (float& x : c) x = offset + (onLattice ? float(lattice(rng)) + 0.5f : pos(rng));
    const float half = i % 2 == 1 && i / 2 < wide ? 0.95f : 0.5f;
    s.add(c[0], c[1], c[2], half, half, half);
  }
  return s;
}

/// Boxes of about one size are searched by home cell, on a grid of cells as large as the largest sampled box:
/// the same pairs as brute force; boxes larger than the cells (wide), huge boxes through their cells and one
/// by one, and a grid kept for stage 11 after the search, which the next search then uses.
TEST(GridPairFinder, SearchByHomeCell) {
  Scene s = unitBoxCloud(12000, -20.0f, 25, 21);
  s.add(0, -20, 0, 30, 1, 30);  // a ground under the cloud, in its lowest cells: tested one by one
  s.add(5, 5, 5, 7, 0.3f, 7);   // a plate over a few slabs' cells: tested through its cells
  s.add(10, 5, -8, 1, 25, 1);   // a pillar along the slab axis
  gpucol::ProxyArrays view = s.view();
  const std::vector<std::uint64_t> reference = gpucol::BruteForcePairFinder::pairsOf(view);
  ASSERT_GT(reference.size(), 5000u);
  gpucol::PairFinderOptions o;
  o.bruteForceBelow = 0;
  auto finder = gpucol::makeCpuPairFinder();
  std::vector<std::uint64_t> pairs;
  auto search = [&](const char* what) {
    SCOPED_TRACE(what);
    finder->findPairs(view, o, pairs);
    ASSERT_EQ(pairs, gpucol::BruteForcePairFinder::pairsOf(view));
  };
  search("first");
  const gpucol::PairFinderStats& st = finder->stats();
  EXPECT_TRUE(st.homeCells);
  EXPECT_GE(st.slabs, 8u);
  EXPECT_EQ(st.hugeProxies, 3u);
  EXPECT_GT(st.wideBoxes, 0u) << "boxes larger than the sampled ones span three home cells";
  EXPECT_LT(st.wideBoxes, 100u);
  EXPECT_GT(st.cellSize, 1.0f);
  EXPECT_LT(st.cellSize, 1.01f) << "as large as the largest sampled box";
  // Few moved: the grid kept after the first search (the size rule's, not the home grid) serves.
  std::vector<std::uint8_t> moved(s.flags.size(), 0);
  view.moved = moved.data();
  auto moveFew = [&](std::size_t first) {
    std::fill(moved.begin(), moved.end(), std::uint8_t(0));
    for (std::size_t i = first; i < moved.size(); i += 50) {
      s.minY[i] += 0.3f, s.maxY[i] += 0.3f;
      moved[i] = 1;
    }
  };
  moveFew(0);
  search("few moved after the first");
  EXPECT_TRUE(st.incremental);
  std::fill(moved.begin(), moved.end(), std::uint8_t(1));
  search("all moved");
  EXPECT_TRUE(st.homeCells);
  EXPECT_FALSE(st.incremental);
  moveFew(7);
  search("few moved after all moved");
  EXPECT_TRUE(st.homeCells);
  moveFew(13);
  search("few moved again");
  EXPECT_TRUE(st.incremental);
}

/// Unit boxes far from the origin, where a float's step is 1/16 (cellOf rounds), and in a plane of touching
/// boxes: the same pairs by home cell.
TEST(GridPairFinder, SearchByHomeCellFarAwayAndFlat) {
  const Scene far = unitBoxCloud(6000, 1e6f, 0, 22);
  Scene flat;
  for (int x = 0; x < 70; ++x)
    for (int z = 0; z < 70; ++z) flat.add(float(x), 0.0f, float(z), 0.5f, 0.5f, 0.5f);
  for (const auto& [scene, what] : {std::pair<const Scene*, const char*>(&far, "far"),
                                    std::pair<const Scene*, const char*>(&flat, "flat")}) {
    SCOPED_TRACE(what);
    gpucol::PairFinderOptions o;
    o.bruteForceBelow = 0;
    auto finder = gpucol::makeCpuPairFinder();
    std::vector<std::uint64_t> pairs;
    finder->findPairs(scene->view(), o, pairs);
    EXPECT_EQ(pairs, gpucol::BruteForcePairFinder::pairsOf(scene->view()));
    EXPECT_TRUE(finder->stats().homeCells);
  }
}

/// Random scenes of boxes of about one size, where the search by home cell serves (from 4,096 binned boxes):
/// dense and sparse, on a lattice of touching boxes, flat, far from the origin, with a few wider boxes,
/// points, holes, static boxes, filters and sometimes a ground; the same pairs as brute force under the
/// automatic tiling and with slabs always, at the default slab size and at a random one.
TEST(GridPairFinder, SearchByHomeCellOnRandomScenes) {
  int byHomeCell = 0;
  for (std::uint32_t seed = 0; seed < 16; ++seed) {
    std::mt19937 rng(seed);
    auto uniform = [&](float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(rng); };
    const int n = 4200 + int(rng() % 3000);
    const float half = uniform(0.05f, 2.0f);
    const float side = half * std::cbrt(float(n)) * uniform(0.6f, 4.0f);  // about 60 to 0.2 pairs per box
    const float origin = rng() % 4 == 0 ? uniform(-1e6f, 1e6f) : 0.0f;
    const bool lattice = rng() % 3 == 0, flat = rng() % 5 == 0;
    Scene s;
    for (int i = 0; i < n; ++i) {
      float c[3], h[3];
      for (int a = 0; a < 3; ++a) {
        c[a] = origin + uniform(-side, side);
        h[a] = half * uniform(0.6f, 1.0f);
        if (lattice) c[a] = origin + std::round((c[a] - origin) / (2 * half)) * 2 * half, h[a] = half;
      }
      if (flat) c[1] = origin;
      if (rng() % 200 == 0) h[rng() % 3] *= uniform(1.0f, 6.0f);  // wider than the cells
      if (rng() % 300 == 0) h[0] = h[1] = h[2] = 0.0f;             // a point
      const std::uint8_t flag = rng() % 50 == 0   ? 0                 // a hole
                                : rng() % 20 == 0 ? gpucol::kProxyActive | gpucol::kProxyStatic
                                                  : gpucol::kProxyActive;
      s.add(c[0], c[1], c[2], h[0], h[1], h[2], flag, rng() % 10 == 0 ? 2 : 1, rng() % 10 == 0 ? ~2 : -1);
    }
    if (rng() % 4 == 0) s.add(origin, origin, origin, side, 0.5f, side);  // a ground through the middle
    const std::vector<std::uint64_t> reference = gpucol::BruteForcePairFinder::pairsOf(s.view());
    auto finder = gpucol::makeCpuPairFinder();
    for (auto tiling : {gpucol::SlabTiling::Auto, gpucol::SlabTiling::Always}) {
      gpucol::PairFinderOptions o;
      o.slabTiling = tiling;
      if (rng() % 2) o.slabBoxes = 64 + rng() % 2000;
      std::vector<std::uint64_t> pairs;
      finder->findPairs(s.view(), o, pairs);
      ASSERT_EQ(pairs, reference) << "seed " << seed << " tiling " << int(tiling) << " byHomeCell "
                                  << finder->stats().homeCells << " wide " << finder->stats().wideBoxes;
      byHomeCell += finder->stats().homeCells;
    }
  }
  EXPECT_GE(byHomeCell, 16) << "most of these scenes are searched by home cell";
}

/// SlabTiling::Auto and AnySize search a scene of fewer than 2,048 binned boxes in whatever slabs its grid
/// gives, as many as it fills or fewer (a grid of 4 layers), and leave a big scene that gives fewer than 8
/// (all boxes at one spot: one cell, one slab) to the whole-grid search, which spreads that cell's candidates
/// over threads.
TEST(GridPairFinder, SmallScenesInAnySlabsTheirGridGives) {
  struct Case {
    const char* what;
    Scene scene;
    std::uint32_t minSlabs, maxSlabs;
  };
  Scene pile;
  for (int i = 0; i < 3000; ++i) pile.add(1.0f, 2.0f, 3.0f, 0.5f, 0.5f, 0.5f);
  const Case cases[] = {{"300 boxes", uniformCloud(300, 8.0f, 0.8f, 51), 1, 1000},
                        {"1000 boxes", uniformCloud(1000, 12.0f, 0.8f, 52), 3, 1000},
                        {"1800 boxes in few layers", uniformCloud(1800, 4.0f, 0.8f, 53), 2, 6},
                        {"3000 at one spot", pile, 0, 0}};
  for (const Case& c : cases)
    for (auto tiling : {gpucol::SlabTiling::Auto, gpucol::SlabTiling::AnySize}) {
      auto finder = gpucol::makeCpuPairFinder();
      gpucol::PairFinderOptions o;
      o.slabTiling = tiling;
      std::vector<std::uint64_t> pairs;
      finder->findPairs(c.scene.view(), o, pairs);
      const std::vector<std::uint64_t> reference = gpucol::BruteForcePairFinder::pairsOf(c.scene.view());
      ASSERT_GE(reference.size(), 50u) << c.what;
      EXPECT_EQ(pairs, reference) << c.what;
      EXPECT_TRUE(finder->stats().usedGrid) << c.what;
      EXPECT_GE(finder->stats().slabs, c.minSlabs) << c.what;
      EXPECT_LE(finder->stats().slabs, c.maxSlabs) << c.what;
    }
}

/// Beyond kMaxSlabBoxes (2^18) binned boxes of about one size, Auto and AnySize search by home cell in slabs,
/// with the whole grid's pairs (Off), in a first search (whose grid both keep for stage 11) and in one where
/// all moved.
TEST(GridPairFinder, SlabSearchAtAnySize) {
  const Scene s = uniformCloud(270000, 90.0f, 0.6f, 17);
  std::vector<std::uint8_t> moved(s.flags.size(), 1);
  gpucol::ProxyArrays view = s.view();
  std::vector<std::uint64_t> whole, slabs, byHomeCell;
  for (auto tiling : {gpucol::SlabTiling::Off, gpucol::SlabTiling::AnySize, gpucol::SlabTiling::Auto}) {
    SCOPED_TRACE(tiling == gpucol::SlabTiling::Off    ? "whole"
                 : tiling == gpucol::SlabTiling::Auto ? "auto"
                                                      : "any size");
    auto finder = gpucol::makeCpuPairFinder();
    gpucol::PairFinderOptions o;
    o.slabTiling = tiling;
    std::vector<std::uint64_t>& pairs = tiling == gpucol::SlabTiling::Off    ? whole
                                        : tiling == gpucol::SlabTiling::Auto ? byHomeCell
                                                                             : slabs;
    view.moved = nullptr;
    for (int step = 0; step < 2; ++step) {
      std::vector<std::uint64_t> found;
      finder->findPairs(view, o, found);
      EXPECT_EQ(finder->stats().homeCells, tiling != gpucol::SlabTiling::Off);
      if (tiling == gpucol::SlabTiling::Off)
        EXPECT_EQ(finder->stats().slabs, 0u);
      else
        EXPECT_GE(finder->stats().slabs, 8u);
      if (step == 0) pairs = found;
      EXPECT_EQ(found, pairs) << "step " << step;
      view.moved = moved.data();
    }
  }
  ASSERT_GE(whole.size(), 10000u);
  EXPECT_EQ(slabs, whole);
  EXPECT_EQ(byHomeCell, whole);
}

/// SlabBoxReading::Auto reads the boxes in place in a scene of at most 4,096 binned boxes when the copies of
/// the threads' largest slabs would come to more than 8 bytes per binned box (many boxes per slab, or a few
/// large slabs), and copies them otherwise; the pairs are the same either way. Two threads, as on the machine
/// the rule was measured on. (A search by home cell, from 4,096 boxes of about one size, always copies.)
TEST(GridPairFinder, SlabBoxesReadInPlaceWhereTheirCopiesWouldWeighMost) {
  tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
  // A cloud long along x, the axis the slabs cut, and a column across it at x = 0 that fills one slab.
  auto columnAndCloud = [](int cloud, int column) {
    Scene s;
    std::mt19937 rng(62);
    std::uniform_real_distribution<float> along(-90.0f, 90.0f), across(-15.0f, 15.0f);
    for (int i = 0; i < cloud; ++i) s.add(along(rng), across(rng), across(rng), 0.6f, 0.6f, 0.6f);
    for (int i = 0; i < column; ++i) s.add(0.0f, 0.01f * float(i), 0.0f, 0.6f, 0.6f, 0.6f);
    return s;
  };
  struct Case {
    const char* what;
    Scene scene;
    bool inPlace;
  };
  const Case cases[] = {{"1,000 boxes", uniformCloud(1000, 12.0f, 0.8f, 61), true},
                        {"3,500 boxes", columnAndCloud(3500, 0), false},
                        {"3,500 boxes, a column holding 40% of them", columnAndCloud(2100, 1400), true}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    const std::vector<std::uint64_t> reference = gpucol::BruteForcePairFinder::pairsOf(c.scene.view());
    ASSERT_GE(reference.size(), 100u);
    for (auto reading :
         {gpucol::SlabBoxReading::Auto, gpucol::SlabBoxReading::Copy, gpucol::SlabBoxReading::InPlace}) {
      auto finder = gpucol::makeCpuPairFinder();
      gpucol::PairFinderOptions o;
      o.slabBoxReading = reading;
      std::vector<std::uint64_t> pairs;
      finder->findPairs(c.scene.view(), o, pairs);
      EXPECT_EQ(pairs, reference) << int(reading);
      ASSERT_GE(finder->stats().slabs, 2u);
      EXPECT_EQ(finder->stats().slabBoxesInPlace, reading == gpucol::SlabBoxReading::Auto
                                                      ? c.inPlace
                                                      : reading == gpucol::SlabBoxReading::InPlace);
    }
  }
}

TEST(GridPairFinder, DeterministicWhateverTheThreadCount) {
  const Scene s = uniformCloud(20000, 40.0f, 0.8f, 11);
  gpucol::PairFinderOptions o;
  o.bruteForceBelow = 0;
  std::vector<std::uint64_t> many, one;
  gpucol::makeCpuPairFinder()->findPairs(s.view(), o, many);
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    gpucol::makeCpuPairFinder()->findPairs(s.view(), o, one);
  }
  EXPECT_FALSE(many.empty());
  EXPECT_EQ(many, one);
}

}  // namespace
