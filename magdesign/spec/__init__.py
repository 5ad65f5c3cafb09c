"""The spec language: the one table of spec keys (:mod:`magdesign.spec.keys`) and the spec
reference rendered from it (:mod:`magdesign.spec.reference`)."""

from magdesign.spec.keys import KEYS as KEYS
from magdesign.spec.keys import Key as Key
from magdesign.spec.keys import PlausibilityWarning as PlausibilityWarning
from magdesign.spec.keys import UnlistedKeyError as UnlistedKeyError
from magdesign.spec.keys import lookup as lookup
