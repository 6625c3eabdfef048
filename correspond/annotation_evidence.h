// What the annotators said, in rig weights: every decided comparison and the latest champion of
// each expression over a sequence of annotation projects (rounds), each project's sample ids
// resolved through its own correspondences (dataset samples or proposals). The rig head's fit
// and the belief search read the rounds through this.
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "data/dataset.h"

namespace retarget {

struct JudgedComparison {
  std::string expression;              // the group's label: the human expression
  Eigen::VectorXd positive, negative;  // C rig weights each: positive was judged nearer
  bool tie_break = false;              // settled by the geometric tie-break, not by a person
  // The expression's recipe (blendshape weights) in the round's own human dataset, which may
  // hold other expressions than the current one's (e.g. blends annotated beside the recipes);
  // empty for a face-folder dataset.
  std::map<std::string, double> recipe;
  std::string annotator;  // who decided it (empty: a tie-break or an inferred one)
};

struct AnnotationEvidence {
  std::map<std::string, Eigen::VectorXd> champions;  // expression -> the latest round's champion, C
  std::vector<JudgedComparison> comparisons;         // in round order, then the store's order
};

// `derived`: also the comparisons inferred by transitivity. Throws retarget::Error naming the
// project for one whose correspondences are over another avatar dataset than `avatar`.
AnnotationEvidence load_annotation_evidence(const std::vector<std::string>& projects, const Dataset& avatar,
                                            bool derived);

}  // namespace retarget
