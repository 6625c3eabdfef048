// Named tensors on disk in LibTorch's own serialization (the zip format of torch.save), so a
// Python user can `torch.load(path)` a file and get a dict of tensors.
#pragma once

#include <torch/torch.h>

#include <map>
#include <string>

namespace retarget {

using TensorMap = std::map<std::string, torch::Tensor>;

// Writes the tensors as one dict, atomically (see core/atomic_file.h). Tensors are stored
// as they are (dtype, shape), moved to the CPU and made contiguous first.
void save_tensors(const std::string& path, const TensorMap& tensors);

// Reads a file written by save_tensors (or Python's torch.save of a dict of tensors).
// Throws retarget::Error naming the file if it is missing, unreadable or not such a dict.
TensorMap load_tensors(const std::string& path);

// The tensor `name` of `tensors`; throws retarget::Error naming `file` and the missing name.
const torch::Tensor& tensor_named(const TensorMap& tensors, const std::string& name, const std::string& file);

}  // namespace retarget
