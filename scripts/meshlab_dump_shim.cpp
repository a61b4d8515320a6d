// Preloaded into MeshLab 2020.09's meshlabserver by scripts/meshlab_2020_09_tables.py: its filter dump
// (meshlabserver -d) then lists each parameter as a script writes it, not by its label.
// RichParameter::fieldDescription() const -> the parameter as <Param name= type= value=.../>.
#include <QDomDocument>
#include <QString>
class RichParameter {
public:
    QDomElement fillToXMLDocument(QDomDocument &doc, bool saveDescriptionAndTooltip) const;
};
extern "C" const QString *_ZNK13RichParameter16fieldDescriptionEv(const RichParameter *self) {
    static QString text;
    QDomDocument doc;
    QDomElement element = self->fillToXMLDocument(doc, false);
    doc.appendChild(element);
    text = doc.toString(-1).trimmed();
    return &text;
}
// ShotfValue::fillToXMLElement asserts in this build: write no value for a camera shot.
extern "C" void _ZNK10ShotfValue16fillToXMLElementER11QDomElement(const void *, QDomElement &) {}
