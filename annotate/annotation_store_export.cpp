// The triplets of AnnotationStore as CSV.
#include <ostream>

#include "annotate/annotation_store.h"
#include "annotate/annotation_store_impl.h"
#include "core/atomic_file.h"

namespace retarget {

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

void AnnotationStore::export_csv(const std::string& path, bool include_derived) const {
  const std::vector<Triplet> rows = triplets(include_derived);
  write_file_atomically(path, [&](std::ostream& out) {
    out << "group,anchor,positive,negative,derived,tie_break\n";
    for (const Triplet& t : rows) {
      out << t.group << ',' << csv_field(t.anchor) << ',' << t.positive << ',' << t.negative << ','
          << (t.derived ? 1 : 0) << ',' << (t.tie_break ? 1 : 0) << '\n';
    }
  });
}

}  // namespace retarget
