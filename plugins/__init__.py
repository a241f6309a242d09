"""fogref's Mitsuba plugins (installed as ``fogref_plugins``), registered for the current variant by
``register()``."""


def register() -> None:
    """Register the fog media, the ``fogtabphase`` phase and the ``fogpath`` integrator with Mitsuba."""
    # here, not at module level: the plugins import Mitsuba, which needs a variant set first
    from fogref_plugins.fog_medium import register as register_media
    from fogref_plugins.fogpath import register as register_integrator
    from fogref_plugins.tab_phase import register as register_phase

    register_phase()
    register_media()
    register_integrator()
