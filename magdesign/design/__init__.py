"""Design problems and their solver: variables with bounds, targets, limits, objective."""

from magdesign.design.problem import Limit as Limit
from magdesign.design.problem import Objective as Objective
from magdesign.design.problem import Problem as Problem
from magdesign.design.problem import Target as Target
from magdesign.design.problem import Variable as Variable
from magdesign.design.report import DesignResult as DesignResult
from magdesign.design.report import DesignSweep as DesignSweep
from magdesign.design.solve import SQP as SQP
from magdesign.design.solve import multistart as multistart
from magdesign.design.solve import solve as solve
from magdesign.design.status import DesignStatus as DesignStatus
from magdesign.design.sweep import sweep as sweep
