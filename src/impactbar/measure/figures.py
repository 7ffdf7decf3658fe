"""The figures a test engineer checks a Kolsky bar test and a drill rod's blow by (matplotlib,
imported when drawing)."""

from __future__ import annotations

__all__ = ["plot_kolsky", "plot_drill_rod"]

def _pyplot(path):
    """matplotlib's pyplot, on the Agg backend where the figure goes to a file."""
    import matplotlib

    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt


def _saved(fig, path):
    """``fig`` saved to ``path`` (and closed) where one is given."""
    if path is not None:
        import matplotlib.pyplot as plt

        fig.savefig(path, dpi=130)
        plt.close(fig)
    return fig


_BAR_OF = {"incident": "incident", "reflected": "incident", "transmitted": "transmitted"}


def plot_kolsky(test, path=None):
    """Three panels: the bars' strains against time with the windows found shaded, the three waves
    at the specimen's faces, and the one-, two- and three-wave stress-strain curves.

    Parameters
    ----------
    test : KolskyTest
    path : str or os.PathLike, optional
        Where to save the figure (its suffix the format).

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _pyplot(path)

    fig, (raw, waves, curve) = plt.subplots(3, 1, figsize=(7.5, 9.5), constrained_layout=True)
    t_us = test.record_time * 1e6
    for name, strain in test.bar_strain.items():
        raw.plot(t_us, strain * 1e3, lw=0.7, label=f"{name} bar")
    for (name, w), color, y in zip(test.windows.items(), ("C0", "C2", "C1"), (0.95, 0.05, 0.95), strict=True):
        raw.axvspan(w.t_start * 1e6, w.t_stop * 1e6, color=color, alpha=0.15)
        raw.text(w.t_start * 1e6, y, f" {name}", transform=raw.get_xaxis_transform(), fontsize=8,
                 va="top" if y > 0.5 else "bottom")
    raw.set(xlabel="time (us)", ylabel="strain (1e-3, tension +)",
            title="bars' strains and the windows found")
    raw.legend(fontsize=8)
    tw = test.time * 1e6
    for name in ("incident", "reflected", "transmitted"):
        waves.plot(tw, getattr(test, name) * 1e3, label=name)
    waves.set(xlabel="time from the incident wave's arrival at the specimen (us)", ylabel="strain (1e-3)",
              title="the waves at the specimen's faces")
    waves.legend(fontsize=8)
    for k in ("1", "2", "3"):
        curve.plot(test.specimen.strain[k], test.specimen.stress[k] / 1e6, label=f"{k}-wave")
    curve.set(xlabel="engineering strain", ylabel="stress (MPa)", title="the specimen's stress-strain")
    curve.legend(fontsize=8)
    return _saved(fig, path)


def plot_drill_rod(test, path=None):
    """The panels of a drill rod's blow: the gauges' strains, the waves at the bit, the bit's
    force-penetration curve and, where the model was fitted, its strains against the measured.

    ``test`` a :class:`~impactbar.measure.DrillRodTest`, ``path`` as :func:`plot_kolsky`'s; returns
    the figure.
    """
    plt = _pyplot(path)

    panels = 4 if test.fit is not None else 3
    fig, axes = plt.subplots(panels, 1, figsize=(7.5, 3.0 * panels), constrained_layout=True)
    raw, waves, curve = axes[:3]
    ms = test.record_time * 1e3
    for name, strain in test.gauge_strain.items():
        raw.plot(ms, strain * 1e3, lw=0.7, label=name)
    raw.set(xlabel="time (ms)", ylabel="strain (1e-3, tension +)", title="the gauges' strains")
    raw.legend(fontsize=8)
    tw = test.waves.time * 1e3
    waves.plot(tw, test.waves.toward * 1e3, label="toward the bit")
    waves.plot(tw, test.waves.away * 1e3, label="back from the bit")
    waves.set(xlabel="time (ms)", ylabel="strain (1e-3)", title="the waves at the bit (two-point separation)")
    waves.legend(fontsize=8)
    curve.plot(test.bit.displacement * 1e3, test.bit.force / 1e3, lw=0.9)
    curve.set(xlabel="penetration (mm)", ylabel="force (kN)", title="the bit's force-penetration curve")
    if test.fit is not None:
        station = min(test.fit.comparisons)
        test.fit.comparisons[station].plot(axes[3])
        axes[3].set_title(f"the model's blow fitted, at {station:g} m from the struck end")
    return _saved(fig, path)
