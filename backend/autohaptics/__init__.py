"""autohaptics: turn a movie into 4D haptic effects (vibration, temperature, airflow).

The pipeline is a set of pure functions over numpy arrays (one module per stage:
``loudness``, ``sharpness``, ``booming``, ``low_energy``, ``intensity``, ``saliency``,
``fusion``, ``thermal``, ``airflow``), composed by :mod:`autohaptics.pipeline`.
The one artefact every part shares is :class:`autohaptics.timeline.Timeline`.
"""

__version__ = "0.1.0"

from autohaptics.errors import AutohapticsError, DeviceError, MediaError, ParameterError  # noqa: E402

__all__ = ["__version__", "AutohapticsError", "MediaError", "ParameterError", "DeviceError"]
