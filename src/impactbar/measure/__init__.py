"""Measurements in: strain-gauge recordings to waves, end forces, energies and a Kolsky bar's specimen.

The recording and its bridges (:mod:`~impactbar.measure.recording`), the waves separated at one or
two gauges (:mod:`~impactbar.measure.waves`), the results at a bar's end
(:mod:`~impactbar.measure.results`), a rock's stiffnesses fitted from the bit's force and velocity
(:mod:`~impactbar.measure.rock`), a drill rod's blow from two gauges
(:mod:`~impactbar.measure.drill`), a split-Hopkinson test from raw channels to the stress-strain
curve (:mod:`~impactbar.measure.kolsky`) and its TOML spec (:mod:`~impactbar.measure.spec`), and the
model's blow beside a recording, with its parameters fitted to it (:mod:`~impactbar.measure.model`), a
bar's wave speed fitted from a reflection time (:mod:`~impactbar.measure.reflection`), and a round
bar's dispersion (:mod:`~impactbar.measure.dispersion`).
"""

from .dispersion import disperse, phase_velocity
from .drill import DrillRodTest, analyse_drill_rod
from .kolsky import KolskyTest, analyse_kolsky
from .model import FIT_PARAMETERS, BlowFit, Comparison, compare, fit_blow, gauge_strains, model_rod
from .recording import BRIDGES, Bar, Gauge, Recording, read_tektronix_csv
from .reflection import ReflectionFit, fit_reflection
from .results import (
    EndHistory,
    SpecimenResponse,
    end_history,
    impact_velocity,
    specimen_response,
    wave_energy,
)
from .rock import fit_bilinear_rock
from .spec import read_spec, run_spec
from .waves import Waves, Window, find_pulses, noise_level, separate_one_point, separate_two_point, shift

__all__ = ["BRIDGES", "Bar", "BlowFit", "DrillRodTest", "analyse_drill_rod", "Comparison", "FIT_PARAMETERS",
           "compare", "fit_blow", "gauge_strains", "model_rod", "disperse", "phase_velocity", "EndHistory",
           "Gauge", "KolskyTest", "Recording", "ReflectionFit",
           "SpecimenResponse", "Waves", "Window", "analyse_kolsky", "end_history", "find_pulses",
           "fit_bilinear_rock", "fit_reflection", "impact_velocity", "noise_level", "read_spec",
           "read_tektronix_csv", "run_spec", "separate_one_point", "separate_two_point", "shift",
           "specimen_response", "wave_energy"]
