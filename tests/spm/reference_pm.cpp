// Test-only reference: generated meshes and a deliberately simple half-edge collapser (every candidate
// collapse is simulated on a copy of the face list and the result audited from scratch), so the
// hierarchies it produces are valid by construction rather than by the cleverness of the code under test.
#include "reference_pm.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <stdexcept>
#include <tuple>

#include "spm/hierarchy.h"
#include "spm/refine_info.h"
#include "spm/selective_mesh.h"
#include "spm/vertex_hierarchy.h"
#include "spm/vertex_id.h"

namespace pms::test {
namespace {

using Face = std::array<uint32_t, 3>;

void add_vertex(TestMesh& m, float x, float y, float z) { m.positions.insert(m.positions.end(), {x, y, z}); }
void add_face(TestMesh& m, uint32_t a, uint32_t b, uint32_t c) { m.indices.insert(m.indices.end(), {a, b, c}); }

// Faces of a (rings x segments) quad grid, `wrap_rows` / `wrap_cols` closing it into a cylinder/torus.
void add_grid_faces(TestMesh& m, int rows, int cols, bool wrap_rows, bool wrap_cols) {
  const int vcols = wrap_cols ? cols : cols + 1, vrows = wrap_rows ? rows : rows + 1;
  auto at = [&](int i, int j) { return uint32_t((i % vrows) * vcols + (j % vcols)); };
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) {
      const uint32_t a = at(i, j), b = at(i, j + 1), c = at(i + 1, j + 1), d = at(i + 1, j);
      if ((i + j) % 2 == 0) {
        add_face(m, a, b, c);
        add_face(m, a, c, d);
      } else {
        add_face(m, a, b, d);
        add_face(m, b, c, d);
      }
    }
  }
}

// ---- reference collapser ----

// Audits a face list: no degenerate face, each directed edge once, and around every vertex in `alive`
// exactly one fan (open, or closed with >= 3 faces so no two faces fold onto each other).
bool is_valid_manifold(const std::vector<Face>& faces, const std::vector<uint8_t>& alive) {
  std::set<std::pair<uint32_t, uint32_t>> edges;
  std::vector<std::vector<std::pair<uint32_t, uint32_t>>> around(alive.size());
  for (const Face& f : faces) {
    if (f[0] == f[1] || f[1] == f[2] || f[2] == f[0]) return false;
    for (int k = 0; k < 3; ++k) {
      if (!edges.insert({f[k], f[(k + 1) % 3]}).second) return false;
      around[f[k]].push_back({f[(k + 1) % 3], f[(k + 2) % 3]});
    }
  }
  for (size_t v = 0; v < alive.size(); ++v) {
    const auto& fan = around[v];
    if (!alive[v]) {
      if (!fan.empty()) return false;
      continue;
    }
    if (fan.empty()) return false;
    // (a, b) is followed by (b, c): start where no face ends, or anywhere for a closed fan.
    std::map<uint32_t, uint32_t> next;
    std::set<uint32_t> ends;
    for (auto [a, b] : fan) {
      next[a] = b;
      ends.insert(b);
    }
    uint32_t start = fan[0].first;
    bool open = false;
    for (auto [a, b] : fan)
      if (!ends.count(a)) {
        start = a;
        open = true;
      }
    size_t visited = 0;
    for (uint32_t a = start; next.count(a) && visited <= fan.size();) {
      a = next[a];
      ++visited;
      if (a == start) break;
    }
    if (visited != fan.size() || (!open && fan.size() < 3)) return false;
  }
  return true;
}

struct Collapser {
  const TestMesh& mesh;
  std::vector<Face> current, original;
  std::vector<uint8_t> alive_vertex;
  uint32_t alive_count;
  std::vector<uint32_t> node_of_vertex;  // temporary node: leaves 0..n-1, internal n + k
  std::vector<uint32_t> child_t, child_u, cut_l, cut_r, survivor;
  std::vector<uint32_t> height;

  explicit Collapser(const TestMesh& m) : mesh(m) {
    const uint32_t n = m.vertex_count();
    for (size_t i = 0; i < m.indices.size(); i += 3)
      current.push_back({m.indices[i], m.indices[i + 1], m.indices[i + 2]});
    original = current;
    alive_vertex.assign(n, 1);
    alive_count = n;
    for (uint32_t v = 0; v < n; ++v) {
      node_of_vertex.push_back(v);
      survivor.push_back(v);
    }
    height.assign(n, 0);
  }

  static int slot_of(const Face& f, uint32_t v) { return f[0] == v ? 0 : f[1] == v ? 1 : 2; }

  bool try_collapse(uint32_t t, uint32_t u) {
    if (std::max(height[node_of_vertex[t]], height[node_of_vertex[u]]) + 1 > 40) return false;
    size_t fl = SIZE_MAX, fr = SIZE_MAX;
    std::vector<Face> after, after_original;
    for (size_t f = 0; f < current.size(); ++f) {
      const Face& c = current[f];
      const int st = std::find(c.begin(), c.end(), t) - c.begin();
      if (st < 3 && c[(st + 1) % 3] == u) fl = f;
      if (st < 3 && c[(st + 2) % 3] == u) fr = f;
      if (st < 3 && (c[(st + 1) % 3] == u || c[(st + 2) % 3] == u)) continue;
      Face moved = c;
      if (st < 3) moved[st] = u;
      after.push_back(moved);
      after_original.push_back(original[f]);
    }
    if (fl == SIZE_MAX && fr == SIZE_MAX) return false;
    // Link condition: the only common neighbours are the apexes. The audit below would accept closing a
    // three-edge hole (t, u and one more border vertex), but a one-sided vsplit could not reopen it.
    std::set<uint32_t> nt, common;
    for (const Face& c : current)
      for (int k = 0; k < 3; ++k)
        if (c[k] == t) nt.insert({c[(k + 1) % 3], c[(k + 2) % 3]});
    for (const Face& c : current)
      for (int k = 0; k < 3; ++k)
        if (c[k] == u)
          for (uint32_t w : {c[(k + 1) % 3], c[(k + 2) % 3]})
            if (nt.count(w)) common.insert(w);
    std::set<uint32_t> apexes;
    for (size_t f : {fl, fr})
      if (f != SIZE_MAX)
        for (uint32_t w : current[f])
          if (w != t && w != u) apexes.insert(w);
    if (common != apexes) return false;
    std::vector<uint8_t> alive = alive_vertex;
    alive[t] = 0;
    if (!is_valid_manifold(after, alive)) return false;

    // Dual view: the cut vertex is the input corner of the removed face at its apex.
    auto cut_leaf = [&](size_t f) {
      if (f == SIZE_MAX) return kNone;
      const Face& c = current[f];
      for (int k = 0; k < 3; ++k)
        if (c[k] != t && c[k] != u) return original[f][k];
      return kNone;
    };
    const uint32_t s = uint32_t(survivor.size());
    child_t.push_back(node_of_vertex[t]);
    child_u.push_back(node_of_vertex[u]);
    cut_l.push_back(cut_leaf(fl));
    cut_r.push_back(cut_leaf(fr));
    survivor.push_back(survivor[node_of_vertex[u]]);
    height.push_back(std::max(height[node_of_vertex[t]], height[node_of_vertex[u]]) + 1);
    node_of_vertex[u] = s;
    current = std::move(after);
    original = std::move(after_original);
    alive_vertex = std::move(alive);
    --alive_count;
    return true;
  }

  // One random valid collapse; false when none is left.
  bool collapse_one(std::mt19937& rng) {
    std::vector<std::pair<uint32_t, uint32_t>> candidates;
    for (const Face& f : current)
      for (int k = 0; k < 3; ++k) {
        candidates.push_back({f[k], f[(k + 1) % 3]});
        candidates.push_back({f[(k + 1) % 3], f[k]});
      }
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    std::shuffle(candidates.begin(), candidates.end(), rng);
    for (auto [t, u] : candidates)
      if (try_collapse(t, u)) return true;
    return false;
  }
};

RefineInfo fake_refine(uint32_t node, int depth) {
  // Distinct per node so tests can tell whether the right record reached the right slot.
  return RefineInfo{uint16_t(node), uint16_t(depth), uint16_t(node >> 16), 1, 2, kNoCone};
}

}  // namespace

TestMesh make_octahedron() {
  TestMesh m;
  const float axes[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const auto& a : axes) add_vertex(m, a[0], a[1], a[2]);
  for (int sx = 0; sx < 2; ++sx)
    for (int sy = 0; sy < 2; ++sy)
      for (int sz = 0; sz < 2; ++sz) {
        const uint32_t x = sx, y = 2 + sy, z = 4 + sz;
        // (+x, +y, +z) is CCW from outside; each negative axis mirrors the octant once.
        if ((sx + sy + sz) % 2 == 0) add_face(m, x, y, z);
        else add_face(m, x, z, y);
      }
  return m;
}

TestMesh make_icosphere(int subdivisions) {
  TestMesh m;
  const float p = (1.0f + std::sqrt(5.0f)) / 2;
  const float v[12][3] = {{-1, p, 0},  {1, p, 0},  {-1, -p, 0}, {1, -p, 0}, {0, -1, p},  {0, 1, p},
                          {0, -1, -p}, {0, 1, -p}, {p, 0, -1},  {p, 0, 1},  {-p, 0, -1}, {-p, 0, 1}};
  for (const auto& a : v) add_vertex(m, a[0], a[1], a[2]);
  m.indices = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4,  11, 10, 2,  10, 7, 6, 7, 1, 8,
               3, 9,  4, 3, 4, 2, 3, 2, 6, 3, 6, 8,  3, 8,  9,  4, 9, 5, 2, 4,  11, 6,  2,  10, 8,  6, 7, 9, 8, 1};
  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoint;
    auto mid = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      const uint32_t index = m.vertex_count();
      add_vertex(m, (m.positions[3 * a] + m.positions[3 * b]) / 2,
                 (m.positions[3 * a + 1] + m.positions[3 * b + 1]) / 2,
                 (m.positions[3 * a + 2] + m.positions[3 * b + 2]) / 2);
      midpoint[key] = index;
      return index;
    };
    std::vector<uint32_t> old;
    old.swap(m.indices);
    for (size_t i = 0; i < old.size(); i += 3) {
      const uint32_t a = old[i], b = old[i + 1], c = old[i + 2];
      const uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      add_face(m, a, ab, ca);
      add_face(m, b, bc, ab);
      add_face(m, c, ca, bc);
      add_face(m, ab, bc, ca);
    }
  }
  for (uint32_t i = 0; i < m.vertex_count(); ++i) {
    float* q = &m.positions[3 * i];
    const float len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    for (int k = 0; k < 3; ++k) q[k] /= len;
  }
  return m;
}

TestMesh make_open_grid(int nx, int ny) {
  TestMesh m;
  for (int i = 0; i <= ny; ++i)
    for (int j = 0; j <= nx; ++j) add_vertex(m, float(j), float(i), 0.1f * float((i * 7 + j * 3) % 5));
  add_grid_faces(m, ny, nx, false, false);
  return m;
}

TestMesh make_torus_mesh(int rings, int segments) {
  TestMesh m;
  const float pi = 3.14159265f;
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const float a = 2 * pi * float(i) / float(rings), b = 2 * pi * float(j) / float(segments);
      add_vertex(m, (2 + std::cos(b)) * std::cos(a), (2 + std::cos(b)) * std::sin(a), std::sin(b));
    }
  add_grid_faces(m, rings, segments, true, true);
  return m;
}

TestMesh make_open_cylinder(int rings, int segments) {
  TestMesh m;
  const float pi = 3.14159265f;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const float a = 2 * pi * float(j) / float(segments);
      add_vertex(m, std::cos(a), std::sin(a), float(i));
    }
  add_grid_faces(m, rings, segments, false, true);
  return m;
}

TestMesh make_bipyramid(int ring) {
  TestMesh m;
  const float pi = 3.14159265f;
  for (int j = 0; j < ring; ++j) {
    const float a = 2 * pi * float(j) / float(ring);
    add_vertex(m, std::cos(a), std::sin(a), 0);
  }
  const uint32_t top = uint32_t(ring), bottom = top + 1;
  for (float z : {1.0f, -1.0f}) add_vertex(m, 0, 0, z);
  for (int j = 0; j < ring; ++j) {
    const uint32_t a = uint32_t(j), b = uint32_t((j + 1) % ring);
    add_face(m, top, a, b);
    add_face(m, bottom, b, a);
  }
  return m;
}

ReferenceModel build_reference_model(const TestMesh& mesh, uint32_t seed, uint32_t min_vertices) {
  Collapser c(mesh);
  std::mt19937 rng(seed);
  while (c.alive_count > min_vertices && c.collapse_one(rng)) {
  }
  const uint32_t n = mesh.vertex_count();
  const uint32_t total = uint32_t(c.survivor.size());

  // Roots in input-vertex order get tree-ids 0, 1, ...; a parent is created after its children, so
  // walking the temporary nodes downward hands ids from parents to children.
  std::vector<VertexId> id(total, kNoVertex);
  std::vector<uint32_t> root_of_vertex(n, kNone), roots;
  for (uint32_t v = 0; v < n; ++v) {
    if (!c.alive_vertex[v]) continue;
    root_of_vertex[v] = uint32_t(roots.size());
    id[c.node_of_vertex[v]] = {uint32_t(roots.size()), 1};
    roots.push_back(c.node_of_vertex[v]);
  }
  for (uint32_t k = total - n; k-- > 0;) {
    id[c.child_t[k]] = id[n + k].child(0);
    id[c.child_u[k]] = id[n + k].child(1);
  }
  std::vector<uint32_t> order(total);
  for (uint32_t i = 0; i < total; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return std::tuple(id[a].depth(), id[a].tree, id[a].node) < std::tuple(id[b].depth(), id[b].tree, id[b].node);
  });
  std::vector<uint32_t> index_of(total);
  for (uint32_t i = 0; i < total; ++i) index_of[order[i]] = i;

  ReferenceModel model;
  model.input = mesh;
  Hierarchy& h = model.h;
  h.root_count = uint32_t(roots.size());
  for (const Face& f : c.current)
    for (uint32_t v : f) h.base_faces.push_back(root_of_vertex[v]);
  h.parent.assign(total, kNone);
  h.first_child.assign(total, kNone);
  h.cut_left.assign(total, kNone);
  h.cut_right.assign(total, kNone);
  h.leaf_vertex.assign(total, kNone);
  h.position.resize(3 * size_t(total));
  h.normals.resize(3 * size_t(total));
  h.colors.resize(4 * size_t(total));
  h.refine.resize(total);
  h.tree_id.resize(total);
  h.node_id.resize(total);
  model.leaf_node.resize(n);
  for (uint32_t i = 0; i < total; ++i) {
    const uint32_t node = order[i], leaf = c.survivor[node];
    h.tree_id[i] = id[node].tree;
    h.node_id[i] = id[node].node;
    model.node_by_id[{id[node].tree, id[node].node}] = i;
    h.refine[i] = fake_refine(i, id[node].depth());
    for (int k = 0; k < 3; ++k) {
      h.position[3 * i + k] = mesh.positions[3 * leaf + k];
      h.normals[3 * i + k] = float(leaf) + 0.25f * float(k);
    }
    for (int k = 0; k < 4; ++k) h.colors[4 * i + k] = uint8_t(leaf * 3 + k);
    if (node < n) {
      h.leaf_vertex[i] = node;
      model.leaf_node[node] = i;
      continue;
    }
    const uint32_t k = node - n;
    h.first_child[i] = index_of[c.child_t[k]];
    h.parent[index_of[c.child_t[k]]] = h.parent[index_of[c.child_u[k]]] = i;
    if (index_of[c.child_u[k]] != h.first_child[i] + 1) throw std::logic_error("siblings not adjacent");
    if (c.cut_l[k] != kNone) h.cut_left[i] = index_of[c.cut_l[k]];
    if (c.cut_r[k] != kNone) h.cut_right[i] = index_of[c.cut_r[k]];
  }
  for (uint32_t k = total - n; k-- > 0;) h.split_order.push_back(index_of[n + k]);
  return model;
}

ModelData ReferenceModel::model() const { return model_of(h); }

uint32_t ReferenceModel::node_of(VertexId id) const {
  auto it = node_by_id.find({id.tree, id.node});
  return it == node_by_id.end() ? kNone : it->second;
}

Faces canonical(Faces faces) {
  for (auto& f : faces) std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());
  std::sort(faces.begin(), faces.end());
  return faces;
}

Faces canonical_input(const TestMesh& mesh) {
  Faces faces;
  for (size_t i = 0; i < mesh.indices.size(); i += 3)
    faces.push_back({mesh.indices[i], mesh.indices[i + 1], mesh.indices[i + 2]});
  return canonical(faces);
}

Faces mesh_faces(const SelectiveMesh& mesh) {
  Faces faces;
  for (uint32_t f = 0; f < mesh.face_capacity(); ++f)
    if (mesh.face_alive(f)) faces.push_back({mesh.face(f)[0], mesh.face(f)[1], mesh.face(f)[2]});
  return canonical(faces);
}

Faces dual_view_faces(const SelectiveMesh& mesh, const ReferenceModel& model) {
  Faces faces;
  const ModelData view = model.model();
  for (size_t i = 0; i < model.input.indices.size(); i += 3) {
    std::array<uint32_t, 3> f;
    for (int k = 0; k < 3; ++k) f[k] = mesh.active_ancestor(view.id(model.leaf_node[model.input.indices[i + k]]));
    if (f[0] != f[1] && f[1] != f[2] && f[2] != f[0]) faces.push_back(f);
  }
  return canonical(faces);
}

Faces leaf_faces(const SelectiveMesh& mesh, const ReferenceModel& model) {
  Faces faces = mesh_faces(mesh);
  for (auto& f : faces)
    for (auto& v : f) {
      const uint32_t node = model.node_of(mesh.hierarchy().id(v));
      if (node == kNone || model.h.leaf_vertex[node] == kNone) throw std::logic_error("active vertex is not a leaf");
      v = model.h.leaf_vertex[node];
    }
  return canonical(faces);
}

Faces base_faces(const ReferenceModel& model, const VertexHierarchy& hierarchy) {
  Faces faces;
  for (size_t i = 0; i < model.h.base_faces.size(); i += 3)
    faces.push_back({hierarchy.root_slot(model.h.base_faces[i]), hierarchy.root_slot(model.h.base_faces[i + 1]),
                     hierarchy.root_slot(model.h.base_faces[i + 2])});
  return canonical(faces);
}

}  // namespace pms::test
