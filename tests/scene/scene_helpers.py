"""Shared helpers of the scene and inverse tests: example specs and jaxpr walking."""

import pathlib
import tomllib

import jax

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples"


def example(name: str) -> dict:
    """The parsed spec examples/<name>.toml."""
    with open(EXAMPLES / f"{name}.toml", "rb") as file:
        return tomllib.load(file)


def equations(jaxpr):
    """Every equation of a (closed) jaxpr, sub-jaxprs (scan, cond, pjit) included."""
    jaxpr = getattr(jaxpr, "jaxpr", jaxpr)
    for eqn in jaxpr.eqns:
        yield eqn
        for param in eqn.params.values():
            for sub in param if isinstance(param, (tuple, list)) else (param,):
                if isinstance(sub, (jax.extend.core.ClosedJaxpr, jax.extend.core.Jaxpr)):
                    yield from equations(sub)
