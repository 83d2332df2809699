// Loading and saving surfel models through PCL (hidden here).
//
// Load: .ply, .pcd (point clouds, with or without normals/radii/colours) and .obj
// (triangle meshes become surfels at their vertices with area-weighted normals;
// point-only files are loaded as clouds). Clouds without normals get them estimated
// and oriented outward consistently; missing radii are estimated from neighbour spacing.
// Save: .ply and .pcd with positions, normals, radii (and colours when present).
#pragma once

#include <cstdint>
#include <string>

#include "surfeledit/core/surfel_model.hpp"

namespace surfeledit {

struct LoadParams {
  int normal_k = 16;             // neighbours for normal estimation when the file has no normals
  std::uint64_t max_points = 0;  // refuse (TooLarge) a header announcing more points than this; 0: no limit
};

// Throws Error(Io | InvalidArgument | NotFound | TooLarge) naming the file and the problem. Only regular
// files are read; the counts a PLY/PCD/OFF header announces are checked against the file's size (and
// max_points) before anything is allocated for them (model_headers.hpp in src/). Meshes (OBJ, PLY with faces, OFF,
// STL) give one surfel per vertex a face uses, with area-weighted face normals (mesh_files.hpp in src/); an OFF file
// without faces is a point set, like a PLY, PCD or OBJ without faces (the file's normals, else estimated ones).
SurfelArrays load_surfels(const std::string& path, LoadParams params = {});
// Whether load_surfels reads files of extension `ext` (lower case, with its dot: ".ply", ".pcd", ".obj", ".off",
// ".stl", ".xyz", ".pwn"), and the list as an error message's hint. OFF: ASCII only. XYZ and PWN are text, a point per line: x y z, or x y z nx ny nz.
bool loadable_extension(const std::string& ext);
const char* loadable_formats();
void save_surfels(const std::string& path, const SurfelArrays& arrays);

}  // namespace surfeledit
