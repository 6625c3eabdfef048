#include "models/chebyshev_conv.h"

#include <ATen/Parallel.h>

#include <algorithm>
#include <initializer_list>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/config.h"
#include "core/error.h"

namespace retarget {

namespace {

// A sparse [V, V] operator in compressed rows, built from a coalesced COO tensor: the entries of
// row i are columns[start[i] .. start[i + 1]) with values[...], columns ascending.
struct SparseRows {
  torch::Tensor start;    // [V + 1] int64
  torch::Tensor columns;  // [nnz] int64
  torch::Tensor values;   // [nnz], the operator's dtype
};

// Coalesced COO is sorted by (row, column), so its columns and values already are CSR's; only
// the row starts are counted. O(nnz + V), small next to one product.
SparseRows compressed_rows(const torch::Tensor& coo) {
  const torch::Tensor l = coo.coalesce();  // no-op when already coalesced (graph_operator())
  const int64_t vertices = l.size(0);
  const torch::Tensor indices = l._indices();
  const torch::Tensor rows = indices[0].contiguous();
  SparseRows out{torch::zeros({vertices + 1}, torch::kInt64), indices[1].contiguous(), l._values().contiguous()};
  const int64_t* row = rows.data_ptr<int64_t>();
  int64_t* start = out.start.data_ptr<int64_t>();
  for (int64_t p = 0; p < rows.numel(); ++p) ++start[row[p] + 1];
  for (int64_t i = 0; i < vertices; ++i) start[i + 1] += start[i];
  return out;
}

// The transpose by a counting sort over columns; rows stay ascending within each new row.
SparseRows transposed(const SparseRows& a) {
  const int64_t vertices = a.start.numel() - 1;
  const int64_t nnz = a.columns.numel();
  SparseRows t{torch::zeros({vertices + 1}, torch::kInt64), torch::empty({nnz}, torch::kInt64),
               torch::empty({nnz}, a.values.options())};
  const int64_t* start = a.start.data_ptr<int64_t>();
  const int64_t* column = a.columns.data_ptr<int64_t>();
  int64_t* t_start = t.start.data_ptr<int64_t>();
  int64_t* t_column = t.columns.data_ptr<int64_t>();
  for (int64_t p = 0; p < nnz; ++p) ++t_start[column[p] + 1];
  for (int64_t i = 0; i < vertices; ++i) t_start[i + 1] += t_start[i];
  std::vector<int64_t> next(t_start, t_start + vertices);
  AT_DISPATCH_FLOATING_TYPES(a.values.scalar_type(), "chebyshev_conv_transpose", [&] {
    const scalar_t* value = a.values.data_ptr<scalar_t>();
    scalar_t* t_value = t.values.data_ptr<scalar_t>();
    for (int64_t i = 0; i < vertices; ++i) {
      for (int64_t p = start[i]; p < start[i + 1]; ++p) {
        const int64_t q = next[column[p]]++;
        t_column[q] = i;
        t_value[q] = value[p];
      }
    }
  });
  return t;
}

// t itself if its channels (dim 2) are adjacent in memory, else a contiguous copy. (contiguous()
// would return a [B, V, 1] tensor with any stride unchanged.)
torch::Tensor unit_channel_stride(const torch::Tensor& t) {
  return t.stride(2) == 1 ? t : t.clone(torch::MemoryFormat::Contiguous);
}

// A [B, V, C] tensor with unit channel stride as a pointer and two strides (none if undefined).
template <typename T>
struct RowView {
  explicit RowView(const torch::Tensor& t)
      : data(t.defined() ? t.data_ptr<std::remove_const_t<T>>() : nullptr),
        batch_stride(t.defined() ? t.stride(0) : 0),
        row_stride(t.defined() ? t.stride(1) : 0) {}
  T* row(int64_t b, int64_t i) const { return data + b * batch_stride + i * row_stride; }

  T* data;
  int64_t batch_stride, row_stride;
};

// out = alpha * (A x) + plus - minus for every sample of a batch, where x, plus, minus and out
// are [B, V, C] views with unit channel stride (plus and minus undefined for none). Rows are
// summed in column order, as torch::mm does for a coalesced COO operator.
void propagate(const SparseRows& a, double alpha, const torch::Tensor& x, const torch::Tensor& plus,
               const torch::Tensor& minus, const torch::Tensor& out) {
  const int64_t batch = x.size(0), vertices = x.size(1), channels = x.size(2);
  for (const torch::Tensor* t : std::initializer_list<const torch::Tensor*>{&x, &plus, &minus, &out}) {
    TORCH_INTERNAL_ASSERT(!t->defined() || (t->sizes() == x.sizes() && t->stride(2) == 1));
  }
  const int64_t* start = a.start.data_ptr<int64_t>();
  const int64_t* column = a.columns.data_ptr<int64_t>();
  AT_DISPATCH_FLOATING_TYPES(x.scalar_type(), "chebyshev_conv_propagate", [&] {
    const scalar_t* value = a.values.data_ptr<scalar_t>();
    const RowView<const scalar_t> x_rows(x), plus_rows(plus), minus_rows(minus);
    const RowView<scalar_t> out_rows(out);
    const auto scale = static_cast<scalar_t>(alpha);
    // ~32k multiply-adds per task.
    const int64_t grain = std::max<int64_t>(1, 32768 / (8 * channels));
    at::parallel_for(0, batch * vertices, grain, [&](int64_t begin, int64_t end) {
      for (int64_t r = begin; r < end; ++r) {
        const int64_t b = r / vertices, i = r % vertices;
        const scalar_t* xb = x_rows.row(b, 0);
        const int64_t x_stride = x_rows.row_stride;
        scalar_t* o = out_rows.row(b, i);
        for (int64_t c = 0; c < channels; ++c) o[c] = 0;
        for (int64_t p = start[i]; p < start[i + 1]; ++p) {
          const scalar_t w = value[p];
          const scalar_t* xr = xb + column[p] * x_stride;
          for (int64_t c = 0; c < channels; ++c) o[c] += w * xr[c];
        }
        if (scale != scalar_t(1)) {
          for (int64_t c = 0; c < channels; ++c) o[c] *= scale;
        }
        if (plus_rows.data) {
          const scalar_t* s = plus_rows.row(b, i);
          for (int64_t c = 0; c < channels; ++c) o[c] += s[c];
        }
        if (minus_rows.data) {
          const scalar_t* s = minus_rows.row(b, i);
          for (int64_t c = 0; c < channels; ++c) o[c] -= s[c];
        }
      }
    });
  });
}

// [T_0(A) x | T_1(A) x | ... | T_order(A) x] of x [B, V, C] as one [B, V, C * (order + 1)] tensor
// (term-major), by T_k = 2 A T_(k-1) - T_(k-2). order >= 1.
torch::Tensor chebyshev_terms(const SparseRows& a, const torch::Tensor& x_, int64_t order) {
  const torch::Tensor x = unit_channel_stride(x_);
  const int64_t channels = x.size(2);
  const torch::Tensor terms = torch::empty({x.size(0), x.size(1), channels * (order + 1)}, x.options());
  auto term = [&](int64_t k) { return terms.narrow(2, k * channels, channels); };
  term(0).copy_(x);
  for (int64_t k = 1; k <= order; ++k) {
    propagate(a, k == 1 ? 1.0 : 2.0, term(k - 1), {}, k == 1 ? torch::Tensor() : term(k - 2), term(k));
  }
  return terms;
}

// sum_k T_k(A) u_k of u = [u_0 | u_1 | ... | u_order] [B, V, C * (order + 1)] (term-major) -> [B, V, C],
// by Clenshaw's recurrence: b_k = u_k + 2 A b_(k+1) - b_(k+2) down to k = 1, then
// sum = u_0 + A b_1 - b_2. order >= 1.
torch::Tensor chebyshev_sum(const SparseRows& a, const torch::Tensor& u_, int64_t order) {
  const torch::Tensor u = unit_channel_stride(u_);
  const int64_t channels = u.size(2) / (order + 1);
  auto term = [&](int64_t k) { return u.narrow(2, k * channels, channels); };
  std::vector<torch::Tensor> b(order + 1);
  b[order] = term(order);
  for (int64_t k = order - 1; k >= 0; --k) {
    b[k] = torch::empty({u.size(0), u.size(1), channels}, u.options());
    propagate(a, k == 0 ? 1.0 : 2.0, b[k + 1], term(k), k + 2 <= order ? b[k + 2] : torch::Tensor(), b[k]);
    if (k + 2 <= order) b[k + 2] = torch::Tensor();
  }
  return b[0];
}

void save_operator(torch::autograd::AutogradContext* ctx, const SparseRows& a, int64_t order) {
  ctx->saved_data["start"] = a.start;
  ctx->saved_data["columns"] = a.columns;
  ctx->saved_data["values"] = a.values;
  ctx->saved_data["order"] = order;
}

// For backward: A^T. The kernels are not differentiable themselves, so a second derivative
// (backward with create_graph) would be silently wrong; refuse it instead.
SparseRows saved_transpose(torch::autograd::AutogradContext* ctx) {
  TORCH_CHECK(!torch::GradMode::is_enabled(),
              "ChebyshevConv: double backward (create_graph) is not supported with a sparse operator on CPU");
  return transposed({ctx->saved_data["start"].toTensor(), ctx->saved_data["columns"].toTensor(),
                     ctx->saved_data["values"].toTensor()});
}

// The two maps are each other's adjoints up to transposing A (T_k(A)^T = T_k(A^T)), so each one's
// backward is the other on A^T: no layout change, concatenation or transposed sparse product.
struct ChebyshevTerms : public torch::autograd::Function<ChebyshevTerms> {
  static torch::Tensor forward(torch::autograd::AutogradContext* ctx, const torch::Tensor& x, const SparseRows& a,
                               int64_t order) {
    save_operator(ctx, a, order);
    return chebyshev_terms(a, x, order);
  }
  static torch::autograd::variable_list backward(torch::autograd::AutogradContext* ctx,
                                                 torch::autograd::variable_list grads) {
    const int64_t order = ctx->saved_data["order"].toInt();
    return {chebyshev_sum(saved_transpose(ctx), grads[0], order), torch::Tensor(), torch::Tensor()};
  }
};

struct ChebyshevSum : public torch::autograd::Function<ChebyshevSum> {
  static torch::Tensor forward(torch::autograd::AutogradContext* ctx, const torch::Tensor& u, const SparseRows& a,
                               int64_t order) {
    save_operator(ctx, a, order);
    return chebyshev_sum(a, u, order);
  }
  static torch::autograd::variable_list backward(torch::autograd::AutogradContext* ctx,
                                                 torch::autograd::variable_list grads) {
    const int64_t order = ctx->saved_data["order"].toInt();
    return {chebyshev_terms(saved_transpose(ctx), grads[0], order), torch::Tensor(), torch::Tensor()};
  }
};

}  // namespace

void ChebyshevConvOptions::validate(const std::string& key_path) const {
  require_positive(static_cast<double>(in_), key_path + ".in");
  require_positive(static_cast<double>(out_), key_path + ".out");
  require_non_negative(static_cast<double>(order_), key_path + ".order");
}

ChebyshevConvImpl::ChebyshevConvImpl(torch::Tensor laplacian_, const ChebyshevConvOptions& options_)
    : options(options_), laplacian(std::move(laplacian_)) {
  options.validate();
  if (laplacian.dim() != 2 || laplacian.size(0) != laplacian.size(1)) {
    throw Error("chebyshev_conv", "expected a square [V, V] graph operator, got " + c10::str(laplacian.sizes()));
  }
  reset();
}

void ChebyshevConvImpl::reset() {
  laplacian = register_buffer("laplacian", laplacian);
  linear = register_module(
      "linear",
      torch::nn::Linear(
          torch::nn::LinearOptions(options.in() * (options.order() + 1), options.out()).bias(options.bias())));
}

void ChebyshevConvImpl::pretty_print(std::ostream& stream) const {
  stream << "retarget::ChebyshevConv(in=" << options.in() << ", out=" << options.out() << ", order=" << options.order()
         << ", bias=" << std::boolalpha << options.bias() << ", vertices=" << laplacian.size(0) << ")";
}

torch::Tensor ChebyshevConvImpl::forward(const torch::Tensor& x) {
  const int64_t vertices = laplacian.size(0);
  TORCH_CHECK(x.dim() == 3 && x.size(1) == vertices && x.size(2) == options.in(), "ChebyshevConv: expected x [B, ",
              vertices, ", ", options.in(), "], got ", x.sizes());
  if (options.order() == 0) return linear->forward(x);  // the only term is x itself
  const bool compressed = laplacian.is_sparse() && laplacian.sparse_dim() == 2 && laplacian.device().is_cpu() &&
                          x.device().is_cpu() && !laplacian.requires_grad() &&
                          x.scalar_type() == laplacian.scalar_type() &&
                          (x.scalar_type() == torch::kFloat || x.scalar_type() == torch::kDouble);
  if (compressed) {
    // Terms stay [B, V, C]-major: the Linear runs on contiguous rows and nothing is permuted.
    const SparseRows a = compressed_rows(laplacian);
    const int64_t order = options.order();
    if (options.out() < options.in()) {
      // Linear first: sum_k T_k(L~) (x W_k^T) is the same map as [T_0 x | ... | T_order x] W^T
      // (W_k: the k-th [out, in] block of W), with sparse products of width out instead of in.
      const torch::Tensor w = linear->weight.view({options.out(), order + 1, options.in()})
                                  .transpose(0, 1)
                                  .reshape({(order + 1) * options.out(), options.in()});
      const torch::Tensor y = ChebyshevSum::apply(torch::matmul(x, w.t()), a, order);
      return options.bias() ? y + linear->bias : y;
    }
    return linear->forward(ChebyshevTerms::apply(x, a, order));
  }
  // Dense operators and other devices: [B, V, in] -> [V, B * in], one product per term for the batch.
  const int64_t batch = x.size(0);
  const int64_t in = options.in();
  const torch::Tensor t0 = x.permute({1, 0, 2}).reshape({vertices, batch * in});
  std::vector<torch::Tensor> terms{t0};
  terms.push_back(torch::mm(laplacian, t0));
  for (int64_t k = 2; k <= options.order(); ++k) {
    terms.push_back(2.0 * torch::mm(laplacian, terms[k - 1]) - terms[k - 2]);
  }
  for (auto& t : terms) t = t.view({vertices, batch, in});
  // [V, B, in * (order + 1)] -> [B, V, in * (order + 1)]
  const torch::Tensor features = torch::cat(terms, 2).permute({1, 0, 2});
  return linear->forward(features);
}

}  // namespace retarget
