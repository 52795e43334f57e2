"""Plots of one or more sweep stores (matplotlib), read the way a gear-noise study reads them.

1. DTE RMS against mesh frequency, one curve per torque (and per swept parameter value), with the
   linearized mesh natural frequency f_n and its 1/2 and 1/3 marked: a mesh order k resonates
   where k·f_m = f_n. Filled markers: points where contact was lost (some samples without a
   loaded tooth pair), the regime of the softening shift and the jump.
2. Contact-loss share against mesh frequency (the nonlinear regime at a glance).
3. A waterfall of mesh orders against speed (order tracking, as in a Campbell diagram): each
   speed's DTE spectrum at orders 1–3, drawn at the orders' frequencies k·f_m on that speed's row,
   size and colour by amplitude; the orders light up where they cross f_n.
4. The dynamic factor K_v (maximum dynamic / static mesh force) against speed.

    python -m gearfmu.plots sweep.zarr [other.zarr …] --png sweep.png
"""

from __future__ import annotations

import argparse
import itertools
from pathlib import Path

import numpy as np

from . import store


def _curves(ds):
    """(label, selection) per torque × parameter combination, a selection over speed_rpm."""
    extra = [d for d in ds["status"].dims if d not in ("speed_rpm", "torque_nm")]
    for torque in ds["torque_nm"].values:
        for values in itertools.product(*(ds[d].values for d in extra)):
            sel = {"torque_nm": torque, **dict(zip(extra, values))}
            label = f"{torque:g} N·m" + "".join(f", {d} {v:g}" for d, v in zip(extra, values))
            yield label, sel


def plot_sweeps(paths: list, png: Path, waterfall_store: int = 0) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    datasets = [(Path(p), store.load(p)) for p in paths]
    fig, axes = plt.subplots(2, 2, figsize=(14, 9.5))
    ax_rms, ax_loss, ax_fall, ax_kv = axes[0, 0], axes[1, 0], axes[0, 1], axes[1, 1]
    styles = ["-", "--", ":", "-."]
    colors = itertools.cycle(plt.rcParams["axes.prop_cycle"].by_key()["color"])
    for n, (path, ds) in enumerate(datasets):
        name = ds.attrs.get("fmu_name", path.stem)
        for label, sel in _curves(ds):
            color = next(colors)
            point = ds.sel(sel)
            done = point["status"].values == store.DONE
            f_m = point["mesh_frequency_hz"].values[done]
            rms = point["dte_rms_m"].values[done] * 1e6
            lost = point["contact_loss_share"].values[done] > 0
            ax_rms.plot(f_m, rms, styles[n % 4], color=color, lw=1.0, label=f"{name}: {label}")
            ax_rms.plot(f_m[lost], rms[lost], "o", color=color, ms=3)
            failed = point["status"].values == store.FAILED
            if failed.any():
                speeds = point["speed_rpm"].values[failed]
                f_failed = ds.attrs["teeth_1"] * speeds / 60.0
                ax_rms.plot(f_failed, np.zeros_like(f_failed), "x", color=color, ms=6,
                            label=f"{name}: {label}, failed points")
            ax_loss.plot(f_m, point["contact_loss_share"].values[done], styles[n % 4], color=color, lw=1.0)
            ax_kv.plot(point["speed_rpm"].values[done], point["dynamic_factor"].values[done], styles[n % 4],
                       color=color, lw=1.0, label=f"{name}: {label}")
            f_n = float(point["mesh_natural_frequency_hz"].values)
            if np.isfinite(f_n):
                for ax in (ax_rms, ax_loss):
                    for k, alpha in ((1, 0.9), (2, 0.6), (3, 0.4)):
                        ax.axvline(f_n / k, color=color, ls=styles[n % 4], lw=0.7, alpha=alpha)
                ax_rms.annotate(f"f_n = {f_n:.0f} Hz", (f_n, 0), xytext=(3, 3), textcoords="offset points",
                                color=color, fontsize=7, rotation=90, va="bottom")
    ax_rms.set_ylabel("DTE RMS (µm)")
    ax_rms.set_title("DTE RMS; lines: linearized f_n, f_n/2, f_n/3; dots: contact lost")
    ax_rms.legend(fontsize=7)
    ax_loss.set_xlabel("mesh frequency f_m = z₁·n₁/60 (Hz)")
    ax_loss.set_ylabel("contact-loss share of samples")
    ax_loss.set_xlim(ax_rms.get_xlim())
    ax_kv.set_xlabel("gear-1 speed (rpm)")
    ax_kv.set_ylabel("K_v = max dynamic / static mesh force")
    ax_kv.legend(fontsize=7)

    # Waterfall of one store's first curve: mesh orders 1–3 of the DTE, stacked by speed.
    path, ds = datasets[waterfall_store]
    label, sel = next(_curves(ds))
    point = ds.sel(sel)
    speeds = point["speed_rpm"].values
    done = point["status"].values == store.DONE
    amplitudes = point["dte_order_amplitude_m"].values[done] * 1e6     # (speed, order)
    f_m = ds.attrs["teeth_1"] * speeds[done] / 60.0
    orders = ds["mesh_order"].values
    from matplotlib.colors import LogNorm
    for k, order in enumerate(orders):
        ax_fall.plot(order * ds.attrs["teeth_1"] * speeds / 60.0, speeds, color="0.8", lw=0.5, zorder=0)
        ax_fall.annotate(f"order {order}", (order * f_m[-1], speeds[done][-1]), fontsize=7, ha="right", va="bottom")
    positive = amplitudes[amplitudes > 0]
    norm = LogNorm(vmin=max(positive.min(), positive.max() * 1e-3), vmax=positive.max()) if positive.size else None
    dots = ax_fall.scatter((orders[None, :] * f_m[:, None]).ravel(), np.repeat(speeds[done], len(orders)),
                           c=amplitudes.ravel(), s=10 + 60 * amplitudes.ravel() / max(amplitudes.max(), 1e-30),
                           cmap="viridis", norm=norm)
    fig.colorbar(dots, ax=ax_fall, label="DTE amplitude of the mesh order (µm)")
    f_n = float(point["mesh_natural_frequency_hz"].values)
    if np.isfinite(f_n):
        ax_fall.axvline(f_n, color="k", ls="--", lw=0.8, label=f"f_n = {f_n:.0f} Hz")
    ax_fall.set_xlabel("frequency (Hz)")
    ax_fall.set_ylabel("gear-1 speed (rpm)")
    ax_fall.set_title(f"Waterfall, {ds.attrs.get('fmu_name', path.stem)}, {label}")
    ax_fall.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    Path(png).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(png, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m gearfmu.plots", description=__doc__.split("\n")[0])
    parser.add_argument("stores", type=Path, nargs="+")
    parser.add_argument("--png", type=Path, required=True)
    args = parser.parse_args(argv)
    plot_sweeps(args.stores, args.png)
    print(f"wrote {args.png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
