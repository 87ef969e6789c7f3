"""Fields coupled to the flow through the frozen-coefficient protocol, built outside the flow
problem: the transported strain (and its derivative in Newton's step) and the steady
temperature.
"""
