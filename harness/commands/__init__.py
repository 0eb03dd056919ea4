"""Subcommands of ``djl-fmu`` (one module each, with ``register(subparsers)``)."""
