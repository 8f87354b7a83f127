"""The paper's figures, one script per figure (Xie, Sze & Zhou 2015, Figs. 4-13 and 19-22).

    solidshell figures [FIG ...] [--quick] [--out DIR]
    python -m paper_figures.fig05 [--quick] [--out DIR]

Each writes ``figNN.png`` and ``figNN.json`` (the runs behind it: settings, wall time, drape
coefficient, folds, and how the figure differs from the paper's).  See registry.py.
"""
