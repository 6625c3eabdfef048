#!/usr/bin/env python3
"""How far unseen people's codes of one expression scatter, for a human dataset and a linear
encoder: the rank-k principal autoencoder that `model.encoder_skip` starts a VAE at
(train/principal_encoder.h), fitted on the dataset's training people and scored on its held-out
ones, in the two figures `retarget eval vae` reports for a human VAE: the normalised feature L1
against the identity-averaged targets (beside the neutral answer's) and the code ratio (mean
distance between codes of one expression across people / between expressions' mean codes).

  scripts/code_scatter.py DATASET [--latent 25] [--training-people N] [--ridge 0.01 1 10]

--training-people keeps the first N training people only: how the ratio falls as the training
people come to span the face model's identity modes. Needs Python 3 with torch and PyYAML (not
part of the build; the measurement behind `default_people` in data/dataset.h).
"""
import argparse

import torch
import yaml


def normalise(x, n):
    y = 1.8 * (x - n["min"]) / (n["max"] - n["min"]) - 0.9
    return y.reshape(x.shape[0], -1).double()


def code_ratio(codes, expression):
    kinds = expression.unique()
    within = []
    for e in kinds:
        z = codes[expression == e]
        m = z.shape[0]
        within.append(torch.cdist(z, z).sum() / (m * (m - 1)))
    means = torch.stack([codes[expression == e].mean(0) for e in kinds])
    between = torch.cdist(means, means).sum() / (len(kinds) * (len(kinds) - 1))
    return (torch.stack(within).mean() / between).item()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dataset")
    parser.add_argument("--latent", type=int, default=25)
    parser.add_argument("--training-people", type=int, default=0)
    parser.add_argument("--ridge", type=float, nargs="+", default=[0.01, 1.0, 10.0],
                        help="lambda as a fraction of the rows' mean square norm (0.01: the skip's)")
    a = parser.parse_args()
    torch.set_grad_enabled(False)

    data = torch.load(f"{a.dataset}/features.pt")
    n = torch.load(f"{a.dataset}/normaliser.pt")
    manifest = yaml.safe_load(open(f"{a.dataset}/manifest.yaml"))
    subjects = manifest["subjects"]
    training = [subjects.index(s) for s in manifest["split"]["train"]]
    if a.training_people > 0:
        training = training[: a.training_people]
    held_out = [subjects.index(s) for s in manifest["split"]["test"]]
    subject, expression = data["subject"], data["expression"]
    train = torch.isin(subject, torch.tensor(training))
    test = torch.isin(subject, torch.tensor(held_out))

    x = normalise(data["features"], n)
    targets = normalise(data["targets"], n)
    x_train, x_test = x[train], x[test]
    e_test = expression[test]
    t_train = targets[expression[train]]

    # The targets' principal basis; codes with unit variance per coordinate, as the decoder's start.
    t_mean = t_train.mean(0)
    _, _, vh = torch.linalg.svd(t_train - t_mean, full_matrices=False)
    basis = vh[: a.latent]
    codes = (t_train - t_mean) @ basis.T
    scale = codes.std(0)
    codes = codes / scale

    x_mean = x_train.mean(0)
    xc, xt = x_train - x_mean, x_test - x_mean
    gram = xc @ xc.T
    mean_square = gram.diagonal().mean()
    neutral_l1 = targets[e_test].abs().mean().item()
    print(f"{a.dataset}: {len(training)} training people ({int(train.sum())} rows), "
          f"{len(held_out)} held out ({int(test.sum())} rows), latent {a.latent}")
    print(f"{'ridge':>8} {'feature L1':>11} {'x neutral':>10} {'code ratio':>11}")
    for ridge in a.ridge:
        eye = torch.eye(gram.shape[0], dtype=gram.dtype)
        dual = torch.linalg.solve(gram + ridge * mean_square * eye, codes)
        z = (xt @ xc.T) @ dual
        rebuilt = (z * scale) @ basis + t_mean
        l1 = (rebuilt - targets[e_test]).abs().mean().item()
        print(f"{ridge:8g} {l1:11.5f} {l1 / neutral_l1:10.3f} {code_ratio(z, e_test):11.3f}")


if __name__ == "__main__":
    main()
