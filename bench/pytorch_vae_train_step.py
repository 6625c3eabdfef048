#!/usr/bin/env python3
"""The paper-size mesh VAE's training step in PyTorch-Python, beside retarget's C++ one
(bench/train_bench.cpp BM_AvatarVaeTrainStep / BM_HumanVaeTrainStep): the same layers
(Chebyshev graph convolutions 9 -> 128 -> 64 -> 64 -> 64 -> 1 of order 2 on the rescaled
normalised Laplacian, dense 300, latent 25, LeakyReLU 0.1, tanh), the same loss (L1 +
1e-5 KL), Adam 1e-4, batch 30, random features in [-0.9, 0.9], written as a PyTorch user would
(torch.sparse.mm for the graph products). Debian's python3-torch uses the same ATen build.

  python3 bench/pytorch_vae_train_step.py MESH.obj --threads 1 [--batch 30] [--steps 20]

Prints one line: mesh, vertices, threads, median seconds per step and samples per second.
"""
import argparse
import statistics
import time

import torch


def read_obj_edges(path):
    vertices, edges = 0, set()
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                vertices += 1
            elif parts[0] == "f":
                idx = [int(p.split("/")[0]) for p in parts[1:]]
                idx = [i - 1 if i > 0 else vertices + i for i in idx]
                for a, b in zip(idx, idx[1:] + idx[:1]):
                    edges.add((min(a, b), max(a, b)))
    return vertices, sorted(edges)


def graph_operator(vertices, edges):
    """L~ = 2 L / lambda_max - I, L = I - D^-1/2 A D^-1/2 (models/graph_operator.h)."""
    e = torch.tensor(edges, dtype=torch.int64)
    rows = torch.cat([e[:, 0], e[:, 1]])
    cols = torch.cat([e[:, 1], e[:, 0]])
    degree = torch.zeros(vertices, dtype=torch.float64).index_add_(0, rows, torch.ones(rows.numel(), dtype=torch.float64))
    inv_sqrt = torch.where(degree > 0, degree.rsqrt(), torch.zeros_like(degree))
    a = -inv_sqrt[rows] * inv_sqrt[cols]
    diag = torch.arange(vertices)
    laplacian = torch.sparse_coo_tensor(torch.stack([torch.cat([rows, diag]), torch.cat([cols, diag])]),
                                        torch.cat([a, (degree > 0).double()]), (vertices, vertices)).coalesce()
    x = torch.ones(vertices, 1, dtype=torch.float64)
    lam = 0.0
    for _ in range(500):
        y = torch.sparse.mm(laplacian, x)
        new = float((x * y).sum() / (x * x).sum())
        x = y / y.norm()
        if abs(new - lam) <= 1e-10 * max(1.0, abs(new)):
            lam = new
            break
        lam = new
    identity = torch.sparse_coo_tensor(torch.stack([diag, diag]), torch.ones(vertices, dtype=torch.float64),
                                       (vertices, vertices))
    return ((2.0 / lam) * laplacian - identity).coalesce().float()


class ChebConv(torch.nn.Module):
    def __init__(self, laplacian, cin, cout, order=2):
        super().__init__()
        self.laplacian, self.order = laplacian, order
        self.linear = torch.nn.Linear(cin * (order + 1), cout)

    def forward(self, x):  # [B, V, C]
        b, v, c = x.shape
        flat = x.permute(1, 0, 2).reshape(v, b * c)
        terms = [flat, torch.sparse.mm(self.laplacian, flat)]
        for _ in range(2, self.order + 1):
            terms.append(2 * torch.sparse.mm(self.laplacian, terms[-1]) - terms[-2])
        stacked = torch.stack(terms, 2).reshape(v, b, c * (self.order + 1)).permute(1, 0, 2)
        return self.linear(stacked)


class MeshVae(torch.nn.Module):
    def __init__(self, laplacian, vertices, channels=(9, 128, 64, 64, 64, 1), hidden=300, latent=25):
        super().__init__()
        self.vertices = vertices
        self.convs = torch.nn.ModuleList(ChebConv(laplacian, a, b) for a, b in zip(channels, channels[1:]))
        self.encoder_hidden = torch.nn.Linear(vertices * channels[-1], hidden)
        self.mean_head = torch.nn.Linear(hidden, latent)
        self.logvar_head = torch.nn.Linear(hidden, latent)
        self.decoder_hidden = torch.nn.Linear(latent, hidden)
        self.decoder_out = torch.nn.Linear(hidden, vertices * channels[0])

    def forward(self, x):
        h = x
        for i, conv in enumerate(self.convs):
            h = conv(h)
            h = torch.tanh(h) if i == len(self.convs) - 1 else torch.nn.functional.leaky_relu(h, 0.1)
        h = torch.nn.functional.leaky_relu(self.encoder_hidden(h.flatten(1)), 0.1)
        mean, logvar = self.mean_head(h), self.logvar_head(h)
        z = mean + torch.exp(0.5 * logvar) * torch.randn_like(mean)
        d = torch.nn.functional.leaky_relu(self.decoder_hidden(z), 0.1)
        return torch.tanh(self.decoder_out(d)).view(x.shape[0], self.vertices, 9), mean, logvar


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("mesh")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--batch", type=int, default=30)
    parser.add_argument("--steps", type=int, default=20)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    torch.manual_seed(0)
    vertices, edges = read_obj_edges(args.mesh)
    model = MeshVae(graph_operator(vertices, edges), vertices)
    adam = torch.optim.Adam(model.parameters(), lr=1e-4)
    x = torch.rand(args.batch, vertices, 9) * 1.8 - 0.9
    times = []
    for step in range(args.steps + 3):
        start = time.perf_counter()
        adam.zero_grad()
        recon, mean, logvar = model(x)
        kl = (-0.5 * (1 + logvar - mean.pow(2) - logvar.exp()).sum(1)).mean()
        loss = torch.nn.functional.l1_loss(recon, x) + 1e-5 * kl
        loss.backward()
        adam.step()
        if step >= 3:  # the first steps warm the allocator up
            times.append(time.perf_counter() - start)
    median = statistics.median(times)
    print(f"pytorch-python {args.mesh}: {vertices} vertices, batch {args.batch}, {args.threads} threads: "
          f"median {median * 1000:.1f} ms a step, {args.batch / median:.1f} samples/s")


if __name__ == "__main__":
    main()
