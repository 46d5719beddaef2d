"""The built-in cost models: unit prices of named quantities (:mod:`.unit_prices`).

Each cost model is an ordinary plugin with an entry point of its own; this
package registers nothing, it only names the classes, so that ``from
rockfall_design_builtins.costs import UnitPrices`` keeps working.
"""

from .unit_prices import UnitPrices, UnitPricesParams

__all__ = ["UnitPrices", "UnitPricesParams"]
