#include "export/script_source.h"

#include <cctype>
#include <charconv>

namespace retarget::script {

// The shortest decimal that reads back as the same double, always with a point or exponent
// so TorchScript sees a float ("0.1", "1.8", "2.0").
std::string literal(double value) {
  char buffer[64];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, value).ptr;
  std::string text(buffer, end);
  if (text.find_first_of(".en") == std::string::npos) text += ".0";
  return text;
}

void check_prefix(const std::string& prefix, const char* who) {
  bool ok = prefix.empty() || std::isalpha(static_cast<unsigned char>(prefix[0])) || prefix[0] == '_';
  for (const char c : prefix) ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '_');
  TORCH_CHECK(ok, who, ": '", prefix, "' cannot start a TorchScript identifier");
}

// A detached float32 CPU copy that shares no storage with the live model.
torch::Tensor frozen(const torch::Tensor& t) {
  return t.detach().to(torch::kCPU, torch::kFloat32).contiguous().clone();
}

// Registers linear's weight and bias as the parameters <name>_weight and <name>_bias and
// returns the TorchScript expression applying it to `input`.
std::string add_linear(torch::jit::Module& module, const torch::nn::Linear& linear, const std::string& name,
                       const std::string& input) {
  module.register_parameter(name + "_weight", frozen(linear->weight), /*is_buffer=*/false);
  std::string bias = "None";
  if (linear->bias.defined()) {
    module.register_parameter(name + "_bias", frozen(linear->bias), /*is_buffer=*/false);
    bias = "self." + name + "_bias";
  }
  return "torch.linear(" + input + ", self." + name + "_weight, " + bias + ")";
}

// A TorchScript line asserting that `var` has the given sizes (-1: any); the message names
// `method` and shows the sizes found.
std::string shape_check(const std::string& method, const std::string& var, const std::vector<int64_t>& sizes,
                        const std::string& meaning) {
  std::string condition = var + ".dim() == " + str(static_cast<int64_t>(sizes.size()));
  std::string shape = "[";
  for (size_t i = 0; i < sizes.size(); ++i) {
    if (sizes[i] >= 0) condition += " and " + var + ".size(" + str(static_cast<int64_t>(i)) + ") == " + str(sizes[i]);
    shape += (i ? ", " : "") + (sizes[i] >= 0 ? str(sizes[i]) : std::string("B"));
  }
  shape += "]";
  return "    assert " + condition + ", \"" + method + ": expected " + var + " of shape " + shape + " (" + meaning +
         "), got \" + str(" + var + ".shape)\n";
}

// The first line of an exception's message, without LibTorch's C++ backtrace.
std::string first_line(const std::exception& e) {
  const auto* c10_error = dynamic_cast<const c10::Error*>(&e);
  const std::string text = c10_error ? c10_error->what_without_backtrace() : e.what();
  const size_t start = text.find_first_not_of(" \n");
  if (start == std::string::npos) return text;
  return text.substr(start, text.find('\n', start) - start);
}

}  // namespace retarget::script
