#include "spm/vertex_id.h"

namespace pms {

std::string to_string(VertexId v) {
  std::string s(1, '<');  // appended piecewise: g++ 12 flags "<" + std::string with a bogus -Wrestrict
  s += std::to_string(v.tree);
  s += ',';
  s += std::to_string(v.node);
  s += '>';
  return s;
}

}  // namespace pms
