"""One error root: everything tumble_ros refuses on purpose is a TumbleRosError."""
import pytest

from tumble_ros import errors
from tumble_ros.analysis import AnalysisError
from tumble_ros.analysis.figures import FigureExistsError, FigurePathError
from tumble_ros.core import IntegrationError, Scenario, ScenarioError
from tumble_ros.core.analytic import ModelNotApplicable
from tumble_ros.ensembles import EnsembleRunError, EnsembleStoreError
from tumble_ros.io import McapError, MessageDefinitionError


@pytest.mark.parametrize('error, package_class', [
    (ScenarioError, errors.CoreError),
    (IntegrationError, errors.CoreError),
    (ModelNotApplicable, errors.CoreError),
    (errors.NodeError, errors.TumbleRosError),
    (McapError, errors.IoError),
    (MessageDefinitionError, errors.IoError),
    (EnsembleStoreError, errors.IoError),
    (EnsembleRunError, errors.CoreError),
    (AnalysisError, errors.AnalysisError),
    (FigurePathError, errors.AnalysisError),
    (FigureExistsError, errors.AnalysisError),
])
def test_each_error_derives_from_its_package_class(error, package_class):
    assert issubclass(error, package_class) and issubclass(package_class, errors.TumbleRosError)


def test_a_refused_scenario_is_caught_by_the_root():
    with pytest.raises(errors.TumbleRosError, match='^duration: '):
        Scenario(duration=-1.0)
    with pytest.raises(ValueError):  # and still a ValueError, as callers caught it before
        Scenario(duration=-1.0)
