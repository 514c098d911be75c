#pragma once
// Nesting levels of the faces of a CGAL constrained triangulation: which faces lie inside
// the polygons its constraints draw (the fit domain and its holes; a hole polygon to fill).

#include <deque>
#include <unordered_map>
#include <utility>

namespace tbs::detail {

// Nesting level of every face of a constrained triangulation: 0 for the infinite face, one
// more across each edge for which crosses(a, b) holds (a, b: the edge's finite vertices).
// Odd levels are inside the outermost polygons, even levels above 0 inside their holes.
template <class Tr, class Crosses>
std::unordered_map<typename Tr::Face_handle, int> nesting_levels(const Tr& t, Crosses crosses) {
  std::unordered_map<typename Tr::Face_handle, int> level;
  std::deque<std::pair<typename Tr::Face_handle, int>> queue{{t.infinite_face(), 0}};
  level[t.infinite_face()] = 0;
  while (!queue.empty()) {
    auto [f, l] = queue.front();
    queue.pop_front();
    for (int k = 0; k < 3; ++k) {
      auto g = f->neighbor(k);
      if (level.count(g)) continue;
      auto va = f->vertex(Tr::cw(k)), vb = f->vertex(Tr::ccw(k));
      const bool across = !t.is_infinite(va) && !t.is_infinite(vb) && f->is_constrained(k) && crosses(va, vb);
      level[g] = across ? l + 1 : l;
      if (across)
        queue.push_back({g, l + 1});
      else
        queue.push_front({g, l});
    }
  }
  return level;
}

}  // namespace tbs::detail
