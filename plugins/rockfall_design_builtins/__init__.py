"""The built-in plugins of rockfall-design: ordinary plugins that use only the
public ``rockfall_design`` API and register through the ``rockfall_design``
entry-point group, exactly as a third party's would."""
