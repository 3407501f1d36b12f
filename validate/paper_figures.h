// The paper's figures (Keul, Koß, Schröder, Müller: two-level Line Space; ../shared/reference/),
// typed in for side-by-side comparison.  Measured on an i7-6800k and a GTX 1080 with GLSL compute,
// 1024x1024 images.  Absolute speed is not comparable with ours; ratios, RMSE and MB per LS are.
#pragma once

#include "common/model/structure_name.h"

#include <array>
#include <string>

namespace ls::paper {

inline const std::array<std::string, 5> kScenes = {"FIREPLACE", "BREAKFAST", "LIVING ROOM", "SALLE DE BAIN",
                                                    "BUNNY SCENE"};
inline const std::array<double, 5> kSceneTriangles = {143e3, 269e3, 576e3, 1231e3, 4467e3};
inline const std::array<int, 5> kSceneObjects = {49, 45, 78, 39, 64};

struct Build {
  double ls, mb, seconds;
};

// Table 2 and Table 3, one row per Line Space configuration (the same twelve in both).
struct Config {
  StructureKind kind;
  int depth, subdivision;
  std::array<Build, 5> table2;  // per scene, in kScenes order
  double mrays_per_s;           // Table 3, averaged over all scenes
  std::array<double, 3> rmse;   // Table 3: LS from bounce 1, 2, 3
};

inline const std::array<Config, 12> kConfigs = {{
    {StructureKind::FlatLs, 8, 6, {{{226, 28.1, 0.82}, {186, 26.4, 1.58}, {198, 38.4, 1.58}, {207, 53.4, 3.07}, {245, 141.2, 10.29}}}, 377.0, {.030, .011, .004}},
    {StructureKind::FlatLs, 10, 6, {{{763, 80.9, 2.17}, {641, 70.8, 4.11}, {620, 81.5, 2.77}, {706, 98.0, 4.97}, {954, 199.5, 13.05}}}, 313.0, {.025, .008, .002}},
    {StructureKind::FlatLs, 12, 6, {{{2223, 206.0, 5.83}, {2185, 214.3, 12.49}, {1936, 199.1, 6.33}, {2628, 238.7, 11.90}, {3750, 407.4, 23.78}}}, 268.3, {.021, .006, .002}},
    {StructureKind::TwoLevelLs, 0, 6, {{{49, 8.4, 0.81}, {45, 11.0, 1.11}, {78, 22.8, 1.95}, {39, 35.5, 2.64}, {9, 2.5, 0.24}}}, 208.0, {.023, .008, .003}},
    {StructureKind::TwoLevelLs, 4, 6, {{{526, 53.4, 1.62}, {648, 68.5, 2.89}, {940, 109.2, 3.60}, {467, 76.1, 3.87}, {24, 3.8, 0.29}}}, 120.2, {.012, .004, .002}},
    {StructureKind::TwoLevelLs, 8, 6, {{{4195, 344.9, 8.27}, {7351, 646.5, 21.78}, {7373, 631.7, 15.92}, {6296, 490.5, 18.55}, {264, 20.2, 0.98}}}, 92.5, {.009, .003, .002}},
    {StructureKind::FlatLs, 4, 10, {{{16, 18.0, 0.52}, {16, 21.8, 1.12}, {16, 29.6, 1.36}, {16, 46.9, 2.59}, {16, 132.9, 9.83}}}, 622.6, {.044, .019, .006}},
    {StructureKind::FlatLs, 6, 10, {{{63, 57.2, 1.24}, {54, 51.4, 2.70}, {59, 70.1, 2.05}, {59, 85.1, 3.31}, {63, 170.9, 11.01}}}, 440.6, {.033, .012, .004}},
    {StructureKind::FlatLs, 8, 10, {{{226, 184.8, 3.78}, {186, 147.1, 7.89}, {198, 190.6, 4.31}, {207, 194.2, 6.66}, {245, 294.4, 15.39}}}, 346.6, {.018, .007, .002}},
    {StructureKind::TwoLevelLs, 0, 10, {{{49, 38.0, 1.24}, {45, 35.8, 2.05}, {78, 74.7, 2.71}, {39, 62.3, 3.21}, {9, 7.0, 0.30}}}, 201.8, {.015, .005, .002}},
    {StructureKind::TwoLevelLs, 4, 10, {{{526, 366.7, 6.50}, {648, 450.0, 14.10}, {940, 708.4, 12.66}, {467, 362.1, 10.45}, {24, 16.7, 0.59}}}, 117.7, {.008, .003, .001}},
    {StructureKind::TwoLevelLs, 6, 10, {{{1634, 1058.4, 19.62}, {2328, 1549.6, 47.93}, {2931, 1926.1, 37.25}, {1719, 1079.0, 32.82}, {72, 42.6, 1.49}}}, 102.2, {.006, .002, .001}},
}};

inline constexpr double kFlatBvhMraysPerS = 70.7;      // Table 3
inline constexpr double kTwoLevelBvhMraysPerS = 34.3;  // Table 3
inline constexpr double kFlatBvhMb = 21.0;             // Table 4

// Table 4: structure per bounce 1..3 (bounce 0, the rasterized primary, is exact in ours) as our
// schedule, and the paper's average memory, MRays/s and RMSE.
struct ScheduleRow {
  const char* paper_name;
  const char* schedule;
  double mb, mrays_per_s, rmse;  // rmse < 0: none (the exact reference)
};

inline const std::array<ScheduleRow, 7> kSchedules = {{
    {"F-BVH, F-BVH, F-BVH", "bvh", 21.0, 70.7, -1.0},
    {"F-BVH, F-BVH, 2L-LS 1", "bvh,bvh,bvh,2l-ls:4:6", 83.2, 87.2, .002},
    {"F-BVH, 2L-LS 1, 2L-LS 1", "bvh,bvh,2l-ls:4:6", 83.2, 103.7, .004},
    {"F-BVH, 2L-LS 1, 2L-LS 2", "bvh,bvh,2l-ls:4:6,2l-ls:0:10", 126.8, 130.9, .004},
    {"F-BVH, 2L-LS 2, 2L-LS 2", "bvh,bvh,2l-ls:0:10", 64.6, 158.1, .005},
    {"F-BVH, 2L-LS 1, F-LS", "bvh,bvh,2l-ls:4:6,f-ls:8:6", 140.7, 189.3, .006},
    {"F-BVH, F-LS, F-LS", "bvh,bvh,f-ls:8:6", 78.5, 274.9, .011},
}};

}  // namespace ls::paper
