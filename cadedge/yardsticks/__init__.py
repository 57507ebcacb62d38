"""Yardsticks for judging the refiners, never imported by the pipeline: analytic test curves
(:mod:`~cadedge.yardsticks.analytic`), high-accuracy reference lengths
(:mod:`~cadedge.yardsticks.reference`) and the sampled DP optimum (:mod:`~cadedge.yardsticks.optimum`).
Tests, benchmarks and users comparing grids use them.
"""
