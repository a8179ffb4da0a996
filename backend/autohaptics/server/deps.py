"""Dependencies of the routes, as short aliases; tests swap them with ``app.dependency_overrides``."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Request

from autohaptics.server.chair import ChairService
from autohaptics.server.jobs import JobRunner
from autohaptics.server.pictures import Pictures
from autohaptics.server.settings import Settings
from autohaptics.server.store import Store
from autohaptics.server.styles import Styles
from autohaptics.server.composer import Composer


def get_settings(request: Request) -> Settings:
    return request.app.state.settings


def get_store(request: Request) -> Store:
    return request.app.state.store


def get_runner(request: Request) -> JobRunner:
    return request.app.state.runner


def get_composer(request: Request) -> Composer:
    return request.app.state.composer


def get_chair(request: Request) -> ChairService:
    return request.app.state.chair


def get_styles(request: Request) -> Styles:
    return request.app.state.styles


def get_pictures(request: Request) -> Pictures:
    return request.app.state.pictures


SettingsDep = Annotated[Settings, Depends(get_settings)]
StoreDep = Annotated[Store, Depends(get_store)]
RunnerDep = Annotated[JobRunner, Depends(get_runner)]
ComposerDep = Annotated[Composer, Depends(get_composer)]
ChairDep = Annotated[ChairService, Depends(get_chair)]
StylesDep = Annotated[Styles, Depends(get_styles)]
PicturesDep = Annotated[Pictures, Depends(get_pictures)]
