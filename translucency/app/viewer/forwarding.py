"""Members one object keeps for another: a viewer's attributes that are its state's, a state's that are its
appearance's or its light rig's. Each is declared in one line on the class that shows it."""

from __future__ import annotations

import functools


def attribute_of(holder: str, name: str, doc: str | None = None) -> property:
    """A property read from and written to ``self.<holder>.<name>``, documented by ``doc`` (default: whose it is)."""

    def get(owner):
        return getattr(getattr(owner, holder), name)

    def put(owner, value):
        setattr(getattr(owner, holder), name, value)

    return property(get, put, doc=doc or f"The {holder}'s ``{name}``.")


def method_of(holder: str, method, then: str | None = None):
    """A method that calls ``method`` (a function of ``self.<holder>``'s class) on ``self.<holder>``, then
    ``self.<then>()`` when given, and returns what ``method`` returned; its name and docstring are ``method``'s."""

    @functools.wraps(method)
    def forward(owner, *args, **kwargs):
        answer = method(getattr(owner, holder), *args, **kwargs)
        if then is not None:
            getattr(owner, then)()
        return answer

    return forward
