// Triangle rasterization into depth images: the camera's pinhole view (simulator, model
// outlines) and a top-down height map (pile building). One scan-conversion serves both.
#pragma once

#include <utility>
#include <vector>

#include "core/camera.hpp"
#include "core/image.hpp"
#include "model/mesh.hpp"

namespace pipeloc {

struct DepthTarget {
  Image<float> z_mm;              // along the optical axis; 0 where nothing was drawn
  Image<int> label;               // -1 where nothing was drawn
  Image<Eigen::Vector3f> normal;  // unit face normal in camera frame (towards the camera)

  void reset(int width, int height);
};

// Draws the mesh at model_to_cam, keeping the nearest surface per pixel centre.
void render_perspective(const Mesh& mesh, const Pose& model_to_cam, const Intrinsics& k, int label,
                        DepthTarget* target);

struct PixelBox {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // inclusive
  bool empty() const { return x1 < x0 || y1 < y0; }
};

// The mesh's vertices in the camera frame and their pixels: each vertex is moved and projected
// once, not once per face it belongs to. Buffers sized once, to the largest mesh drawn.
struct ProjectedMesh {
  std::vector<Eigen::Vector3d> cam;
  std::vector<Eigen::Vector2d> px;
  // Where reserved for the image's rows: in each row of render_depth_in_box's box, columns that
  // hold every pixel it drew there (first > last where none), so that a loop over the render may
  // skip the rest of the box.
  std::vector<int> row_first, row_last;
  void reserve(const Mesh& mesh, int image_rows = 0) {
    cam.assign(mesh.vertices.size(), Eigen::Vector3d::Zero());
    px.assign(mesh.vertices.size(), Eigen::Vector2d::Zero());
    row_first.assign(std::size_t(image_rows), 0);
    row_last.assign(std::size_t(image_rows), -1);
  }
  // Whether the drawn columns are kept for an image of `height` rows.
  bool has_rows(int height) const { return int(row_first.size()) >= height; }
  // The columns of row y of `box` holding every pixel the last render drew there: those kept
  // (first > last where none), else the box's whole row. An empty box (a mesh beside the image,
  // its rows within the image's) drew nothing and kept no row: none.
  std::pair<int, int> drawn_columns(const PixelBox& box, int y, int height) const {
    if (!has_rows(height) || box.empty()) return {box.x0, box.x1};
    return {row_first[std::size_t(y)], row_last[std::size_t(y)]};
  }
};

// Depth of the mesh alone, drawn into the part of z_mm it covers (cleared first); the rest of
// z_mm is untouched. Returns that box (empty if the mesh is off-screen or behind the camera).
// `projected` must have been reserved for this mesh (or a larger one). For a mesh known to be
// closed (`winding` not open), the faces turned away from the camera are skipped: the nearest
// surface along a ray into a closed mesh is always one facing the camera.
PixelBox render_depth_in_box(const Mesh& mesh, const Pose& model_to_cam, const Intrinsics& k,
                             Image<float>* z_mm, ProjectedMesh* projected, Winding winding = Winding::open);

// A height map over the world XY plane: cell (i, j) has centre (origin + i*cell, origin + j*cell).
struct HeightMap {
  double origin_x_mm = 0, origin_y_mm = 0, cell_mm = 2;
  Image<float> z_mm;

  Eigen::Vector2d to_cell(double x, double y) const {
    return {(x - origin_x_mm) / cell_mm, (y - origin_y_mm) / cell_mm};
  }
  // Height at a world point (nearest cell); `outside` when off the map.
  float at(double x, double y, float outside) const;
};

enum class Envelope { top, bottom };

// Draws the mesh at model_to_world into the map, keeping the highest (top) or lowest (bottom)
// surface per cell. Cells the mesh does not cover keep their value.
void render_height(const Mesh& mesh, const Pose& model_to_world, Envelope which, HeightMap* map);

}  // namespace pipeloc
