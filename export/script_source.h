// Helpers for writing TorchScript source by hand (export/vae_export.cpp, export/bundle_export.cpp):
// the C++ frontend cannot script its modules, so exports register tensors on a
// torch::jit::Module and define() generated source that uses them.
#pragma once

#include <torch/script.h>
#include <torch/torch.h>

#include <cstdint>
#include <exception>
#include <string>
#include <vector>

namespace retarget::script {

// The shortest decimal that reads back as the same double, always with a point or exponent so
// TorchScript sees a float ("0.1", "1.8", "2.0").
std::string literal(double value);

inline std::string str(int64_t value) { return std::to_string(value); }

// Throws (TORCH_CHECK, naming `who`) unless `prefix` can start a TorchScript identifier ("" is fine).
void check_prefix(const std::string& prefix, const char* who);

// A detached float32 CPU copy that shares no storage with the live model.
torch::Tensor frozen(const torch::Tensor& t);

// Registers linear's weight and bias as the parameters <name>_weight and <name>_bias and
// returns the TorchScript expression applying it to `input`.
std::string add_linear(torch::jit::Module& module, const torch::nn::Linear& linear, const std::string& name,
                       const std::string& input);

// A TorchScript line asserting that `var` has the given sizes (-1: any, shown as B); the
// message names `method`, what the input means, and the sizes found.
std::string shape_check(const std::string& method, const std::string& var, const std::vector<int64_t>& sizes,
                        const std::string& meaning);

// The first line of an exception's message, without LibTorch's C++ backtrace.
std::string first_line(const std::exception& e);

}  // namespace retarget::script
