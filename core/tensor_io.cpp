#include "core/tensor_io.h"

#include <fstream>
#include <iterator>

#include "core/atomic_file.h"
#include "core/error.h"

namespace retarget {

void save_tensors(const std::string& path, const TensorMap& tensors) {
  c10::Dict<std::string, torch::Tensor> dict;
  for (const auto& [name, tensor] : tensors) dict.insert(name, tensor.detach().to(torch::kCPU).contiguous());
  const std::vector<char> bytes = torch::pickle_save(c10::IValue(dict));
  write_file_atomically(
      path, [&](std::ostream& out) { out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

TensorMap load_tensors(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, "cannot open the tensor file");
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  c10::IValue value;
  try {
    value = torch::pickle_load(bytes);
  } catch (const c10::Error& e) {
    throw Error(path, std::string("not a LibTorch tensor file: ") + e.what_without_backtrace());
  }
  if (!value.isGenericDict()) throw Error(path, "expected a dict of tensors");
  TensorMap out;
  for (const auto& entry : value.toGenericDict()) {
    if (!entry.key().isString() || !entry.value().isTensor())
      throw Error(path, "expected a dict from names to tensors");
    out[entry.key().toStringRef()] = entry.value().toTensor();
  }
  return out;
}

const torch::Tensor& tensor_named(const TensorMap& tensors, const std::string& name, const std::string& file) {
  const auto it = tensors.find(name);
  if (it == tensors.end()) throw Error(file, "has no tensor named \"" + name + "\"");
  return it->second;
}

}  // namespace retarget
